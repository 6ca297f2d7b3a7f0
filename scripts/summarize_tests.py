#!/usr/bin/env python3
"""Counts the test cases in the JUnit XML files that the test command wrote, lists the failures
and prints the closing line "N passed, N failed[, N skipped]". Exit code 1 when anything failed
or nothing passed.

A suite that did not run must not vanish from the count, so besides failing cases these count
as failures:
- a result file that cannot be read, or that holds no test case at all (a test whose
  setUpClass failed leaves `<testsuite errors="1" tests="0">` and nothing else);
- errors or failures that a suite declares in its attributes beyond its failing cases;
- a test that rostest ran (a case of rostest-*.xml) with no rosunit-<name>.xml beside it;
- a folder given with --expect (a step of the test command) that holds no result file.

Usage: summarize_tests.py RESULTS_DIR [--expect SUBDIR ...]
"""
import argparse
import pathlib
import sys
import xml.etree.ElementTree as ET


class Summary:
    def __init__(self):
        self.passed, self.failed, self.skipped = 0, 0, 0
        self.failures = []

    def fail(self, text, count=1):
        self.failed += count
        self.failures.append(text)


def case_problem(case):
    """The failure or error element of a test case, or None."""
    for tag in ("failure", "error"):
        node = case.find(tag)
        if node is not None:
            return node
    return None


def suites_of(root):
    return [root] if root.tag == "testsuite" else list(root.iter("testsuite"))


def declared_problems(suite):
    total = 0
    for attr in ("errors", "failures"):
        try:
            total += int(suite.get(attr, "0"))
        except ValueError:
            pass
    return total


def count_file(path, summary):
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as e:
        summary.fail(f"{path.name}: unreadable result file ({e})")
        return []
    # rostest-*.xml repeats each <test> of a launch file as one case beside the rosunit-*.xml
    # that holds its test methods: count only its failures (a test node that died before
    # writing results shows up there alone).
    summary_only = path.name.startswith("rostest-")
    cases_in_file, suite_failed_outside_cases = 0, False
    rostest_ran = []
    for suite in suites_of(root):
        failing = 0
        for case in suite.findall("testcase"):
            cases_in_file += 1
            name = f"{case.get('classname', '')}.{case.get('name', '')}"
            problem = case_problem(case)
            if problem is not None:
                failing += 1
                text = (problem.get("message") or problem.text or "").strip()[:300]
                summary.fail(f"{path.name}: {name}: {text}")
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                summary.skipped += 1
                node = case.find("skipped")
                reason = (node.get("message") or node.text or "").strip() if node is not None else ""
                summary.failures.append(f"SKIPPED {path.name}: {name}: {reason[:200]}")
            elif not summary_only:
                summary.passed += 1
            elif case.get("name", "").startswith("test"):
                rostest_ran.append(case.get("name")[len("test"):])
        unexplained = declared_problems(suite) - failing
        if unexplained > 0:
            summary.fail(f"{path.name}: suite {suite.get('name', '?')} declares {unexplained} "
                         "error(s)/failure(s) outside any test case (setUpClass or start-up "
                         "failed, so its tests did not run)", unexplained)
            suite_failed_outside_cases = True
    if cases_in_file == 0 and not suite_failed_outside_cases:
        summary.fail(f"{path.name}: no test case in the file (the suite did not run)")
    return rostest_ran


def summarize(results_dir, expect=()):
    summary = Summary()
    results_dir = pathlib.Path(results_dir)
    files = sorted(results_dir.rglob("*.xml"))
    for f in files:
        for test_name in count_file(f, summary):
            if not (f.parent / f"rosunit-{test_name}.xml").exists():
                summary.fail(f"{f.name}: test {test_name} ran but left no rosunit-{test_name}.xml "
                             "(it did not start or died before writing its results)")
    for sub in expect:
        if not any((results_dir / sub).rglob("*.xml")):
            summary.fail(f"{sub}: no result file (that step of the test command did not run)")
    summary.files = len(files)
    return summary


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results_dir")
    parser.add_argument("--expect", action="append", default=[], metavar="SUBDIR",
                        help="a folder under RESULTS_DIR that must hold a result file")
    args = parser.parse_args(argv)
    s = summarize(args.results_dir, args.expect)
    print(f"\n{s.files} result files in {args.results_dir}")
    for line in s.failures:
        print(line if line.startswith("SKIPPED") else "FAILED " + line)
    tail = f", {s.skipped} skipped" if s.skipped else ""
    print(f"{s.passed} passed, {s.failed} failed{tail}")
    return 0 if s.failed == 0 and s.passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
