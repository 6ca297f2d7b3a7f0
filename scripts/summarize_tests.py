#!/usr/bin/env python3
"""Counts test cases in the JUnit XML files that catkin's run_tests wrote, lists the failures
and prints the closing line "N passed, N failed". Exit code 1 when anything failed or nothing
ran (a crashed test binary leaves a failing "missing result" case, so it counts as failed)."""
import pathlib
import sys
import xml.etree.ElementTree as ET


def main(results_dir):
    passed, failed, skipped, failures = 0, 0, 0, []
    files = sorted(pathlib.Path(results_dir).rglob("*.xml"))
    for f in files:
        try:
            root = ET.parse(f).getroot()
        except ET.ParseError as e:
            failed += 1
            failures.append(f"{f.name}: unreadable result file ({e})")
            continue
        # rostest-*.xml repeats each <test> of a launch file as one case beside the
        # rosunit-*.xml that holds its test methods: count only its failures (a test node
        # that died before writing results shows up there alone).
        summary_only = f.name.startswith("rostest-")
        for case in root.iter("testcase"):
            name = f"{case.get('classname', '')}.{case.get('name', '')}"
            if case.find("failure") is not None or case.find("error") is not None:
                failed += 1
                node = case.find("failure")
                if node is None:
                    node = case.find("error")
                failures.append(f"{f.name}: {name}: {(node.get('message') or node.text or '').strip()[:300]}")
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
            elif not summary_only:
                passed += 1
    print(f"\n{len(files)} result files in {results_dir}")
    for line in failures:
        print("FAILED", line)
    tail = f", {skipped} skipped" if skipped else ""
    print(f"{passed} passed, {failed} failed{tail}")
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
