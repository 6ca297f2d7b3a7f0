#!/usr/bin/env python3
"""A generic device's fail-safe (issue 24) against the real node and the simulator: safe values
at start-up (on_start: safe), when the device's own heartbeat or the bus's is lost, and at node
stop, each checked in the simulator's registers; /diagnostics shows only the fail-safe lines a
generic device has. Also: a NaN reading is published once, not on every poll, and a merged read
the device refuses with exception 03 (too long, as Eastron meters answer) is split. The test
runs the bus node itself, so it can start it on values left set and stop it."""
import copy
import signal
import struct
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from std_msgs.msg import Float64
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import FailsafeEvent, SignalValues
from modbus_rtu_driver.srv import SetValue

import helpers

NODE = "gfsbus"
NS = "/" + NODE + "/"
DRIVE = "7"
SAFE_SPEED = 0xFFE7  # -2.5 Hz at scale 0.1: raw -25 as int16


class GenericFailsafeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_generic_failsafe")
        cls.sim = helpers.sim()
        cls.base_config = helpers.bus_config("generic_failsafe_bus.yaml")
        cls.config = cls.base_config
        cls.events = []
        rospy.Subscriber(NS + "failsafe", FailsafeEvent, cls.events.append)
        cls.statuses = {}
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diag)
        cls.beating = helpers.heartbeat(["/robot/drive_alive", "/robot/alive"])
        cls.node = helpers.BusNode(NODE)

    @classmethod
    def on_diag(cls, msg):
        for s in msg.status:
            cls.statuses[s.name.split(": ", 1)[-1]] = s

    @classmethod
    def tearDownClass(cls):
        cls.stop_node(signal.SIGINT)

    @classmethod
    def start_node(cls):
        # Fresh: a key the previous config had and this one has not must not stay.
        cls.node.start(cls.config, fresh=True)
        return helpers.service(NS + "drive/speed/set", SetValue, timeout=30)

    @classmethod
    def stop_node(cls, sig):
        return cls.node.stop(sig)

    def ensure_node(self):
        if not self.node.running:
            self.start_node()

    def event(self, trigger, since=0):
        return helpers.wait_until(
            lambda: next((e for e in self.events[since:] if e.trigger == trigger and
                          e.device == "drive"), None), 15, "a %s event of drive" % trigger)

    def speed(self, value):
        res = helpers.service(NS + "drive/speed/set", SetValue)(value)
        self.assertTrue(res.success, res.message)

    def run_on(self, state):
        res = helpers.service(NS + "drive/run/set", SetBool)(state)
        self.assertTrue(res.success, res.message)

    def board(self):
        """(speed register, run coil) as the simulated device holds them."""
        return self.sim.get(DRIVE, "holding_register", 0)[0], self.sim.get(DRIVE, "coil", 0)[0]

    def diag(self):
        s = self.statuses.get("device drive")
        return None if s is None else (s, {v.key: v.value for v in s.values})

    def test_1_start_up_writes_the_safe_values_before_any_service(self):
        self.sim.set(DRIVE, "holding_register", 0, 50)  # 5.0 Hz
        self.sim.set(DRIVE, "coil", 0, 1)
        self.start_node()
        # By the time the node takes requests, the device holds its safe values.
        self.assertEqual(self.board(), (SAFE_SPEED, 0))
        e = self.event("start")
        self.assertTrue(e.confirmed, e.message)
        self.assertEqual(list(e.channels), ["speed", "run"])
        self.assertEqual(list(e.values), [-2.5, 0.0])
        self.assertEqual(e.action, "safe")
        # The device's latched ~drive/failsafe holds it for a subscriber that comes after
        # start (docs/ros_api.md: advertised before the on_start write, as the LC board's).
        late = helpers.Latest(NS + "drive/failsafe", FailsafeEvent)
        kept = late.wait(10, lambda m: m.trigger == "start", "the start event")
        self.assertEqual(list(kept.values), [-2.5, 0.0])
        late.sub.unregister()

    def test_2_device_heartbeat_lost_writes_the_safe_values(self):
        self.ensure_node()
        self.speed(3.0)
        self.run_on(True)
        self.assertEqual(self.board(), (30, 1))
        since = len(self.events)
        self.beating.clear()
        try:
            helpers.wait_until(lambda: self.board() == (SAFE_SPEED, 0), 10,
                               "the safe values on the device")
            e = self.event("heartbeat", since)
            self.assertTrue(e.confirmed, e.message)
            self.assertIn("/robot/drive_alive", e.reason)
            # The device's own latched topic keeps it for a late subscriber.
            late = helpers.Latest(NS + "drive/failsafe", FailsafeEvent)
            self.assertEqual(late.wait(10, lambda m: m.trigger == "heartbeat",
                                       "the heartbeat event").values, e.values)
            # /diagnostics: WARN, and only the fail-safe lines a generic device has.
            def warned():
                d = self.diag()
                return d if d and d[0].level == DiagnosticStatus.WARN and \
                    "signals at their safe values after heartbeat" in d[0].message else None
            s, kv = helpers.wait_until(warned, 15, "the heartbeat event in /diagnostics")
            self.assertGreaterEqual(int(kv["fail-safe events"]), 1)
            self.assertEqual(kv["safe values"], "speed -2.5 Hz, run off")
            self.assertEqual(kv["on_start"], "safe")
            self.assertIn("heartbeat", kv["last fail-safe event"])
            for absent in ("safe states", "on_restart", "restarts detected"):
                self.assertNotIn(absent, kv)
        finally:
            self.beating.set()
        # The heartbeat returns: nothing is set back by itself; a new command is taken.
        time.sleep(1.5)
        self.assertEqual(self.board(), (SAFE_SPEED, 0))
        self.speed(1.0)
        self.assertEqual(self.board()[0], 10)

    def test_3_a_nan_reading_is_published_once(self):
        self.ensure_node()
        nan = struct.unpack(">HH", struct.pack(">f", float("nan")))
        received = []
        sub = rospy.Subscriber(NS + "drive/power", Float64, received.append)
        signals = helpers.Latest(NS + "drive/signals", SignalValues)
        try:
            self.sim.set(DRIVE, "input_register", 0, *nan)
            helpers.wait_until(lambda: any(m.data != m.data for m in received), 15,
                               "NaN on drive/power")
            polls = signals.count
            # Ten more polls of the NaN (10 Hz): still one NaN message.
            helpers.wait_until(lambda: signals.count >= polls + 10, 15, "ten more polls")
            self.assertEqual(sum(1 for m in received if m.data != m.data), 1,
                             [m.data for m in received])
            self.sim.set(DRIVE, "input_register", 0, *struct.unpack(">HH", struct.pack(">f", 12.5)))
            helpers.wait_until(lambda: received and received[-1].data == 12.5, 15,
                               "12.5 after the NaN")
        finally:
            sub.unregister()

    def test_4_a_merged_read_refused_with_exception_03_is_split(self):
        self.ensure_node()
        self.sim.set(DRIVE, "input_register", 4, *struct.unpack(">HH", struct.pack(">f", 7.25)))
        signals = helpers.Latest(NS + "drive/signals", SignalValues)

        def energy_read():
            m = signals.msg
            if m is None:
                return None
            i = m.names.index("energy")
            return m.valid[i] and m.values[i] == 7.25
        helpers.wait_until(energy_read, 15, "energy read despite the refused merged read")
        _, kv = helpers.wait_until(
            lambda: self.diag() if self.diag() and "split 0" in self.diag()[1] else None, 15,
            "the split in /diagnostics")
        self.assertIn("refused (exception 03)", kv["split 0"])

    def test_4b_max_is_checked_on_the_value_the_device_would_get(self):
        self.ensure_node()
        flow = helpers.service(NS + "drive/flow/set", SetValue)
        res = flow(90.0)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(DRIVE, "holding_register", 1), [9])
        res = flow(95.0)  # raw 9.5 rounds to 10, which is 100 l/h
        self.assertFalse(res.success)
        self.assertIn("95 l/h would be written as 100 l/h (raw 10), outside -inf to 95 l/h",
                      res.message)
        self.assertEqual(self.sim.get(DRIVE, "holding_register", 1), [9], "nothing written")

    def test_5_node_stop_writes_the_safe_values(self):
        self.ensure_node()
        self.speed(4.0)
        self.run_on(True)
        self.assertEqual(self.board(), (40, 1))
        code = self.stop_node(signal.SIGINT)
        self.assertEqual(code, 0)
        self.assertEqual(self.board(), (SAFE_SPEED, 0))
        self.assertIn("drive: fail-safe shutdown (node stops): speed -2.5 Hz, run off",
                      self.node.output)

    def test_6_bus_heartbeat_lost_reaches_the_generic_device(self):
        self.stop_node(signal.SIGINT)
        config = copy.deepcopy(self.base_config)
        config["heartbeat"] = {"topic": "/robot/alive", "timeout": 1.0}
        del config["devices"]["drive"]["heartbeat"]
        config["devices"]["drive"]["on_start"] = "leave"
        type(self).config = config
        self.sim.set(DRIVE, "holding_register", 0, 50)
        self.start_node()
        self.assertEqual(self.board()[0], 50, "on_start: leave leaves it")
        self.speed(2.0)
        self.run_on(True)
        since = len(self.events)
        self.beating.clear()
        try:
            helpers.wait_until(lambda: self.board() == (SAFE_SPEED, 0), 10,
                               "the safe values after the bus heartbeat")
            e = self.event("heartbeat", since)
            self.assertIn("/robot/alive", e.reason)
        finally:
            self.beating.set()


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "generic_failsafe", GenericFailsafeTest)
