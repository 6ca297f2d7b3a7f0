#!/usr/bin/env python3
"""scripts/summarize_tests.py on small result folders: a suite that did not run must count as
failed, never vanish from the closing line. Each case runs the script as the test command does
and reads its closing line."""
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import unittest

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "summarize_tests.py"

ROSTEST_OK = """<?xml version="1.0" encoding="utf-8"?>
<testsuite errors="0" failures="0" name="unittest.suite.TestSuite" tests="1" time="3.1">
<testcase classname="rostest.runner.RosTest" name="test{name}" time="3.1" /></testsuite>"""
# A test node that died before writing results: rostest's own file says so.
ROSTEST_NODE_DIED = """<?xml version="1.0" encoding="utf-8"?>
<testsuite errors="0" failures="1" name="unittest.suite.TestSuite" tests="1" time="3.1">
<testcase classname="rostest.runner.RosTest" name="test{name}" time="3.1">
<failure message="test [{name}] did not generate test results" type="" /></testcase></testsuite>"""
ROSUNIT_PASSED = """<?xml version="1.0" encoding="utf-8"?>
<testsuite errors="0" failures="0" name="unittest.suite.TestSuite" tests="2" time="1.0">
<testcase classname="__main__.T" name="test_a" time="0.5" />
<testcase classname="__main__.T" name="test_b" time="0.5" /></testsuite>"""
# What rosunit writes when setUpClass raised (seen with a port already in use).
ROSUNIT_SETUPCLASS_ERROR = """<?xml version="1.0" encoding="utf-8"?>
<testsuite errors="1" failures="0" name="unittest.suite.TestSuite" tests="0" time="0.009">
<system-out>&lt;![CDATA[]]&gt;</system-out><system-err>&lt;![CDATA[]]&gt;</system-err></testsuite>"""
GTEST = """<?xml version="1.0" encoding="UTF-8"?>
<testsuites tests="3" failures="0" disabled="0" errors="0" name="AllTests">
<testsuite name="Frame" tests="3" failures="0" disabled="0" skipped="1" errors="0">
<testcase name="Crc" status="run" result="completed" classname="Frame" />
<testcase name="Encode" status="run" result="completed" classname="Frame" />
<testcase name="NeedsRoot" status="run" result="skipped" classname="Frame"><skipped message="needs root" /></testcase>
</testsuite></testsuites>"""


def closing_line(folder, *extra):
    p = subprocess.run([sys.executable, str(SCRIPT), str(folder), *extra], capture_output=True,
                       text=True, timeout=60)
    lines = [l for l in p.stdout.splitlines() if re.match(r"^\d+ passed, \d+ failed", l)]
    assert lines, f"no closing line in:\n{p.stdout}\n{p.stderr}"
    m = re.match(r"^(\d+) passed, (\d+) failed(?:, (\d+) skipped)?$", lines[-1])
    assert m, lines[-1]
    return int(m.group(1)), int(m.group(2)), int(m.group(3) or 0), p.returncode


class SummarizeTests(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)
        (self.dir / "pkg").mkdir()

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, name, text):
        (self.dir / "pkg" / name).write_text(text)

    def test_healthy_rostest_counts_its_cases(self):
        self.write("rostest-test_rostest_share.xml", ROSTEST_OK.format(name="share"))
        self.write("rosunit-share.xml", ROSUNIT_PASSED)
        self.assertEqual(closing_line(self.dir), (2, 0, 0, 0))

    def test_setupclass_error_counts_as_failed(self):
        # The case: rostest's file lists the test without a failure, the rosunit file
        # holds errors="1" tests="0"; the old summary read "2 passed, 0 failed".
        self.write("rostest-test_rostest_transports.xml", ROSTEST_OK.format(name="gateway_drop"))
        self.write("rosunit-gateway_drop.xml", ROSUNIT_SETUPCLASS_ERROR)
        self.write("rostest-test_rostest_share.xml", ROSTEST_OK.format(name="share"))
        self.write("rosunit-share.xml", ROSUNIT_PASSED)
        passed, failed, _, code = closing_line(self.dir)
        self.assertEqual((passed, failed), (2, 1))
        self.assertEqual(code, 1)

    def test_crashed_test_node_counts_once(self):
        self.write("rostest-test_rostest_faults.xml", ROSTEST_NODE_DIED.format(name="faults"))
        self.write("gtest-test_frame.xml", GTEST)
        passed, failed, _, code = closing_line(self.dir)
        self.assertEqual((passed, failed), (2, 1))
        self.assertEqual(code, 1)

    def test_missing_rosunit_file_counts_as_failed(self):
        self.write("rostest-test_rostest_bag.xml", ROSTEST_OK.format(name="bag"))
        self.write("gtest-test_frame.xml", GTEST)
        passed, failed, _, code = closing_line(self.dir)
        self.assertEqual((passed, failed), (2, 1))
        self.assertEqual(code, 1)

    def test_missing_step_counts_as_failed(self):
        self.write("gtest-test_frame.xml", GTEST)
        (self.dir / "sanitizers").mkdir()
        passed, failed, _, code = closing_line(self.dir, "--expect", "sanitizers",
                                               "--expect", "fuzz")
        self.assertEqual((passed, failed), (2, 2))
        self.assertEqual(code, 1)

    def test_unreadable_and_empty_files_count_as_failed(self):
        self.write("gtest-test_frame.xml", GTEST)
        self.write("gtest-test_cut.xml", "<testsuites><testsuite name=")
        self.write("gtest-test_none.xml", '<testsuites tests="0"></testsuites>')
        passed, failed, _, _ = closing_line(self.dir)
        self.assertEqual((passed, failed), (2, 2))

    def test_skipped_cases_are_counted_apart(self):
        self.write("gtest-test_frame.xml", GTEST)
        self.assertEqual(closing_line(self.dir), (2, 0, 1, 0))

    def test_nothing_ran_is_a_failure(self):
        self.assertEqual(closing_line(self.dir)[3], 1)


if __name__ == "__main__":
    # rosunit writes the JUnit file the test command counts (--gtest_output=xml:PATH).
    if any(a.startswith("--gtest_output") for a in sys.argv):
        import rosunit
        rosunit.unitrun("modbus_rtu_driver", "summarize_tests", SummarizeTests)
    else:
        unittest.main()
