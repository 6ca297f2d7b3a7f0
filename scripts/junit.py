#!/usr/bin/env python3
"""Writes one JUnit result file for a check that is not a test framework's (a script's step), so
that summarize_tests.py counts it: one case per name, failed when a message is given. The only
writer of such files: the shell scripts call it, the Python scripts import write_suite.

Usage: junit.py OUT.xml SUITE [--classname NAME] CASE ...
  CASE is NAME (passes), NAME=MESSAGE (fails with that message; read from a file when it
  starts with @) or --skipped NAME=REASON (skipped, with the reason).
  --classname: the cases' classname (default: SUITE)."""
import sys
from xml.sax.saxutils import escape, quoteattr


def case_xml(classname, name, failure="", skipped=None):
    """One <testcase>: failed when `failure` is not empty, skipped when `skipped` is a reason."""
    attrs = "classname=%s name=%s" % (quoteattr(classname), quoteattr(name))
    if skipped is not None:
        return "<testcase %s><skipped message=%s/></testcase>" % (attrs, quoteattr(skipped))
    if failure:
        return "<testcase %s><failure message=%s>%s</failure></testcase>" % (
            attrs, quoteattr(failure.splitlines()[0][:200]), escape(failure))
    return "<testcase %s/>" % attrs


def write_suite(out, suite, cases, classname=None):
    """Writes `cases`, each (name, failure message or "", skip reason or None), as one suite."""
    classname = suite if classname is None else classname
    failures = sum(1 for _, failure, skipped in cases if failure and skipped is None)
    skips = sum(1 for _, _, skipped in cases if skipped is not None)
    body = "".join(case_xml(classname, *case) for case in cases)
    with open(out, "w", encoding="utf-8") as f:
        f.write("<testsuite name=%s tests=\"%d\" failures=\"%d\"%s>%s</testsuite>\n"
                % (quoteattr(suite), len(cases), failures,
                   ' skipped="%d"' % skips if skips else "", body))


def parse_cases(args):
    """The command line's cases as (name, failure message or "", skip reason or None)."""
    cases = []
    skip_next = False
    for arg in args:
        if arg == "--skipped":
            skip_next = True
            continue
        name, _, message = arg.partition("=")
        if skip_next:
            cases.append((name, "", message))
            skip_next = False
            continue
        if message.startswith("@"):
            with open(message[1:]) as f:
                message = f.read()
        cases.append((name, message, None))
    if skip_next:
        raise ValueError("--skipped needs a NAME=REASON after it")
    return cases


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    out, suite, rest = argv[0], argv[1], argv[2:]
    classname = None
    if rest[:1] == ["--classname"]:
        if len(rest) < 3:
            print(__doc__, file=sys.stderr)
            return 2
        classname, rest = rest[1], rest[2:]
    try:
        cases = parse_cases(rest)
    except ValueError as e:
        print("junit.py: %s" % e, file=sys.stderr)
        return 2
    write_suite(out, suite, cases, classname)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
