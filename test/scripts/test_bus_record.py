#!/usr/bin/env python3
"""scripts/bus_record.py, bus.launch's recorder: the bag's name carries the bus node's full name
whatever prefix it is given, so two buses never write one file (docs/recording.md); and its
topics are the node's own and /diagnostics."""
import importlib.util
import pathlib
import re
import sys
import unittest

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "bus_record.py"


def load_script():
    spec = importlib.util.spec_from_file_location("bus_record", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def prefix_of(command):
    return command[command.index("-o") + 1]


class BusRecordTest(unittest.TestCase):
    def setUp(self):
        self.record = load_script().record_command

    def test_the_default_prefix_carries_the_node(self):
        command = self.record("io_bus", "", [], "/robot", "/home/u")
        self.assertEqual(prefix_of(command), "/home/u/modbus_rtu_robot_io_bus")

    def test_a_given_prefix_carries_the_node_too(self):
        command = self.record("io_bus", "/data/robot", ["--split"], "/robot", "/home/u")
        self.assertEqual(prefix_of(command), "/data/robot_robot_io_bus")
        self.assertIn("--split", command)

    def test_two_buses_given_one_prefix_write_two_files(self):
        # The integrator's case: both bus.launch includes given bag:=/data/samebag.
        a = prefix_of(self.record("bag_a", "/data/samebag", [], "", "/home/u"))
        b = prefix_of(self.record("bag_b", "/data/samebag", [], "", "/home/u"))
        self.assertNotEqual(a, b)
        left = prefix_of(self.record("modbus_bus", "/data/samebag", [], "/left", "/home/u"))
        right = prefix_of(self.record("modbus_bus", "/data/samebag", [], "/right", "/home/u"))
        self.assertNotEqual(left, right)

    def test_only_the_nodes_topics_and_diagnostics(self):
        command = self.record("modbus_bus", "", [], "/left", "/home/u")
        patterns = command[command.index("--regex") + 1:]
        self.assertEqual(patterns[1], "^/diagnostics$")
        own = re.compile(patterns[0])
        self.assertTrue(own.match("/left/modbus_bus/relays/outputs"))
        self.assertTrue(own.match("/left/modbus_bus/failsafe"))
        self.assertFalse(own.match("/right/modbus_bus/relays/outputs"))


if __name__ == "__main__":
    # rosunit writes the JUnit file the test command counts (--gtest_output=xml:PATH).
    if any(a.startswith("--gtest_output") for a in sys.argv):
        import rosunit
        rosunit.unitrun("modbus_rtu_driver", "bus_record", BusRecordTest)
    else:
        unittest.main()
