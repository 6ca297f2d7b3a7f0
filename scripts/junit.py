#!/usr/bin/env python3
"""Writes one JUnit result file for a check that is not a test framework's (a script's step), so
that summarize_tests.py counts it: one case per name, failed when a message is given.

Usage: junit.py OUT.xml SUITE NAME[=FAILURE_MESSAGE] ...
  NAME alone passes; NAME=message fails with that message (read from a file when it starts
  with @)."""
import sys
from xml.sax.saxutils import escape, quoteattr


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    out, suite, cases = argv[0], argv[1], argv[2:]
    failures = 0
    body = []
    for case in cases:
        name, _, message = case.partition("=")
        if message.startswith("@"):
            with open(message[1:]) as f:
                message = f.read()
        if message:
            failures += 1
            body.append('<testcase classname=%s name=%s><failure message=%s>%s</failure>'
                        '</testcase>' % (quoteattr(suite), quoteattr(name),
                                         quoteattr(message.splitlines()[0][:200]),
                                         escape(message)))
        else:
            body.append('<testcase classname=%s name=%s/>' % (quoteattr(suite), quoteattr(name)))
    with open(out, "w") as f:
        f.write('<testsuite name=%s tests="%d" failures="%d">%s</testsuite>\n'
                % (quoteattr(suite), len(cases), failures, "".join(body)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
