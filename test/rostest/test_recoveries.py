#!/usr/bin/env python3
"""Failures and recoveries leave a trace: the node started with bus.launch against the simulator
logs when a device answers again and after how long, when the port opens again and after how
long, once (WARN) when a generic signal is refused with the exception, and says in the log and
/diagnostics to check baud, parity and wiring when no device on the bus answers. Numbers read
as people write them (no "1.000000", no "-nan")."""
import os
import re
import shutil
import unittest

import rospy
import rostest
import yaml

from diagnostic_msgs.msg import DiagnosticArray
from rosgraph_msgs.msg import Log

import user_paths as up
from helpers import wait_until
from sim_control import SimControl

NODE = "/modbus_bus"


class RecoveriesTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_recoveries")
        cls.dir = up.scratch_dir("modbus_rtu_recoveries_")
        cls.link = os.path.join(cls.dir, "tty")
        signals = [{"name": "temperature", "table": "input_register", "address": 1,
                    "type": "int16", "scale": 0.1, "unit": "C"},
                   {"name": "bogus", "table": "input_register", "address": 0x50}]
        cls.sim_config = os.path.join(cls.dir, "sim.yaml")
        with open(cls.sim_config, "w") as f:
            yaml.safe_dump({"baud": 9600, "devices": [
                {"type": "lc_relay8", "address": 255},
                {"type": "generic", "address": 1, "signals": signals,
                 "holes": [{"table": "input_register", "from": 0x50, "to": 0x50}]}]}, f)
        config = os.path.join(cls.dir, "bus.yaml")
        with open(config, "w") as f:
            yaml.safe_dump({"port": "/dev/null", "baud": 9600, "devices": {
                "relays": {"type": "lc_relay8", "address": 255, "poll_rate": 5.0},
                "climate": {"type": "generic", "address": 1, "poll_rate": 5.0,
                            "signals": signals}}}, f)
        cls.log = []
        cls.bus_status = []
        cls.subs = [
            rospy.Subscriber("/rosout", Log,
                             lambda m: cls.log.append(m) if m.name == NODE else None),
            rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diagnostics)]
        cls.sim_process = up.start_simulator(cls.sim_config, cls.link, cls.dir)
        cls.sim = SimControl(cls.link + ".ctl")
        cls.launch = up.roslaunch(cls.dir, "roslaunch", "bus.launch", "config:=" + config,
                                  "port:=" + cls.link)
        up.check_device_answers(NODE, "relays", {"type": "lc_relay8"}, cls.dir, cls.launch)

    @classmethod
    def on_diagnostics(cls, msg):
        for s in msg.status:
            if s.name.endswith("bus " + cls.link) or cls.link in s.name:
                cls.bus_status.append(s)

    @classmethod
    def tearDownClass(cls):
        for s in cls.subs:
            s.unregister()
        cls.launch.stop()
        cls.sim_process.stop()
        shutil.rmtree(cls.dir, ignore_errors=True)

    def logged(self, level, pattern):
        return [m.msg for m in self.log if m.level == level and re.search(pattern, m.msg)]

    def wait_logged(self, level, pattern, timeout=30):
        return wait_until(lambda: self.logged(level, pattern), timeout,
                          "a log line matching %r (log: %s)"
                          % (pattern, [m.msg for m in self.log][-10:]))

    def test_1_a_refused_generic_signal_is_logged_once_with_the_exception(self):
        # The first poll comes before /rosout reaches this test: read the node's console
        # (bus.launch has output="screen"), where a user sees it.
        def lines():
            return [l for l in self.launch.output().splitlines()
                    if "climate: signal bogus cannot be read: " in l]
        [line] = wait_until(lines, 30, "the WARN line on the console (console: %s)"
                            % self.launch.tail(10))
        self.assertIn("WARN", line)
        self.assertIn("device answered illegal data address (02)", line)  # the exception
        from modbus_rtu_driver.msg import SignalValues
        seen = []
        sub = rospy.Subscriber(NODE + "/climate/signals", SignalValues, seen.append)
        wait_until(lambda: len(seen) >= 5, 20, "five more polls of climate")
        sub.unregister()
        self.assertEqual(len(lines()), 1, "logged again: %s" % lines())
        self.assertNotIn("signal temperature cannot be read", self.launch.output())

    def test_2_a_device_back_online_says_after_how_long(self):
        self.sim.silence(255, True)
        self.wait_logged(Log.WARN, r"^relays \(lc_relay8 @255\): offline")
        self.sim.silence(255, False)
        [line] = self.wait_logged(Log.INFO, r"^relays: back online after ")
        self.assertRegex(line, r"^relays: back online after \d+(\.\d)? s offline$")

    def test_3_every_device_silent_says_check_baud_parity_and_wiring(self):
        advice = "no device answers: check baud (9600), parity (none) and wiring"
        self.sim.silence(255, True)
        self.sim.silence(1, True)
        try:
            wait_until(lambda: any(advice in s.message for s in self.bus_status), 30,
                       "the bus status saying " + advice)
            self.assertEqual(len(self.logged(Log.WARN, re.escape(advice))), 1)
        finally:
            self.sim.silence(255, False)
            self.sim.silence(1, False)
        self.wait_logged(Log.INFO, r"^climate: back online after ")
        count = len(self.bus_status)
        wait_until(lambda: len(self.bus_status) > count + 1 and
                   advice not in self.bus_status[-1].message, 20, "the advice gone")

    def test_4_the_port_open_again_says_after_how_long(self):
        type(self).sim_process.stop()  # the adapter unplugged: the link goes away
        self.wait_logged(Log.ERROR, r"port not open")
        type(self).sim_process = up.start_simulator(self.sim_config, self.link, self.dir,
                                                    "simulator_again")
        [line] = self.wait_logged(Log.INFO, r"port open again after ")
        self.assertRegex(line, r"^bus %s: port open again after \d+(\.\d)? s$"
                         % re.escape(self.link))

    def test_5_no_number_in_the_log_reads_like_a_machine(self):
        for m in self.log:
            self.assertNotRegex(m.msg, r"\d\.\d{6}\b|-nan", m.msg)


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "recoveries", RecoveriesTest)
