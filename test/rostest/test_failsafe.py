#!/usr/bin/env python3
"""Fail-safe outputs against the real node and the simulator: each trigger is checked in the
simulator's coils, not only in the node's topics. The test runs the bus node itself, so it can
start it on outputs left on and stop it with SIGINT or SIGTERM."""
import signal
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from std_msgs.msg import Bool
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import DigitalStates, FailsafeEvent

import helpers

NODE = "fsbus"
NS = "/" + NODE + "/"
RELAYS, PWM = "8", "1"


class FailsafeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_failsafe")
        cls.sim = helpers.sim()
        cls.config = helpers.bus_config("failsafe_bus.yaml")
        cls.events = []
        rospy.Subscriber(NS + "failsafe", FailsafeEvent, cls.events.append)
        cls.beating = helpers.heartbeat(["/robot/alive"])
        cls.diag = helpers.Latest("/diagnostics", DiagnosticArray)
        cls.node = helpers.BusNode(NODE)

    @classmethod
    def tearDownClass(cls):
        cls.stop_node(signal.SIGINT)

    @classmethod
    def start_node(cls):
        cls.node.start(cls.config)
        return helpers.service(NS + "relays/pump/set", SetBool, timeout=30)

    @classmethod
    def stop_node(cls, sig):
        return cls.node.stop(sig)

    def coils(self, dev, n=8):
        return self.sim.get(dev, "coil", 0, n)

    def event(self, trigger, device="relays", since=0):
        return helpers.wait_until(
            lambda: next((e for e in self.events[since:] if e.trigger == trigger and
                          e.device == device), None), 15, "a %s event of %s" % (trigger, device))

    def set(self, name, state):
        res = helpers.service(NS + name + "/set", SetBool)(state)
        self.assertTrue(res.success, res.message)

    def test_1_start_up_puts_outputs_safe_before_any_command(self):
        self.sim.set(RELAYS, "coil", 0, 1, 1, 0, 1)  # pump, valve on, lamp off, fan on
        self.start_node()
        # By the time the node takes commands, the board is already safe; fan holds.
        self.assertEqual(self.coils(RELAYS, 4), [0, 0, 1, 1])
        e = self.event("start")
        self.assertTrue(e.confirmed, e.message)
        self.assertEqual(list(e.channels), ["pump", "valve", "lamp"])
        self.assertEqual(list(e.states), [False, False, True])
        # The PWM board has no on_start: safe; it is left as it was.
        self.assertEqual(self.coils(PWM, 2), [0, 0])

    def test_2_heartbeat_lost_puts_outputs_safe_and_nothing_comes_back_by_itself(self):
        self.set("relays/pump", True)
        self.set("relays/fan", False)
        self.set("pwm_board/out1", False)
        since = len(self.events)
        self.beating.clear()
        t0 = time.time()
        # Within the timeout (1 s) plus a transaction or two.
        helpers.wait_until(lambda: self.coils(RELAYS, 3) == [0, 0, 1], 5, "relays safe")
        helpers.wait_until(lambda: self.coils(PWM, 2) == [0, 1], 5, "pwm board safe")
        took = time.time() - t0
        self.assertGreater(took, 0.5, "safe states came before the heartbeat timed out")
        self.assertEqual(self.event("heartbeat", "relays", since).confirmed, True)
        self.assertEqual(self.coils(RELAYS, 4)[3], 0)  # fan holds
        # The heartbeat returns: nothing is re-energized ...
        self.beating.set()
        time.sleep(1.5)
        self.assertEqual(self.coils(RELAYS, 3), [0, 0, 1])
        # ... until commanded again.
        self.set("relays/pump", True)
        self.assertEqual(self.coils(RELAYS, 1), [1])

    def test_3_command_timeout_is_a_dead_man(self):
        pub = rospy.Publisher(NS + "relays/valve/command", Bool, queue_size=1)
        helpers.wait_until(lambda: pub.get_num_connections() > 0, 10, "the node subscribed")
        since = len(self.events)
        # Renewed every 0.1 s (timeout 1 s): stays on. First renewed until the first command has
        # reached the board (bounded: a loaded machine may be slow to deliver it), then for 2 s.
        on_by = time.time() + 15.0
        while self.coils(RELAYS, 2)[1] != 1 and time.time() < on_by:
            pub.publish(Bool(True))
            time.sleep(0.1)
        end = time.time() + 2.0
        while time.time() < end:
            pub.publish(Bool(True))
            time.sleep(0.1)
        self.assertEqual(self.coils(RELAYS, 2)[1], 1)
        self.assertFalse([e for e in self.events[since:] if e.trigger == "command_timeout"])
        # No more commands: off within the timeout plus a transaction.
        helpers.wait_until(lambda: self.coils(RELAYS, 2)[1] == 0, 5, "valve off by the dead man")
        e = self.event("command_timeout", "relays", since)
        self.assertEqual(list(e.channels), ["valve"])
        # Services are not affected: a valve set by service stays on.
        self.set("relays/valve", True)
        time.sleep(1.5)
        self.assertEqual(self.coils(RELAYS, 2)[1], 1)

    def test_4_power_cycle_restore_and_safe(self):
        self.set("relays/pump", True)
        self.set("relays/valve", False)
        self.set("relays/lamp", True)
        self.set("relays/fan", True)
        self.set("pwm_board/out0", True)
        self.set("pwm_board/out1", False)
        since = len(self.events)
        self.sim.command("power_cycle")  # every board comes back with its outputs off
        # relays: on_restart restore -> pump and fan on again.
        helpers.wait_until(lambda: self.coils(RELAYS, 4) == [1, 0, 1, 1], 10, "relays restored")
        e = self.event("restart", "relays", since)
        self.assertEqual(e.action, "restore")
        self.assertTrue(e.confirmed, e.message)
        self.assertIn("changed with no command", e.reason)
        # pwm_board: on_restart safe -> out0 off, out1 on.
        helpers.wait_until(lambda: self.coils(PWM, 2) == [0, 1], 10, "pwm board safe")
        self.assertEqual(self.event("restart", "pwm_board", since).action, "safe")

    def test_5_node_stop_sigint_and_sigterm(self):
        for sig in (signal.SIGINT, signal.SIGTERM):
            self.set("relays/pump", True)
            self.set("relays/valve", True)
            self.set("pwm_board/out0", True)
            self.assertEqual(self.coils(RELAYS, 2), [1, 1])
            code = self.stop_node(sig)
            self.assertEqual(code, 0, "exit code after %s" % sig)
            # Written and confirmed before the port closed.
            self.assertEqual(self.coils(RELAYS, 4), [0, 0, 1, 1], "after %s" % sig)
            self.assertEqual(self.coils(PWM, 2), [0, 1], "after %s" % sig)
            self.assertIn("relays: fail-safe shutdown (node stops): pump off, valve off, lamp on",
                          self.node.output)
            self.start_node()

    def test_6_a_device_that_cannot_be_reached_at_stop_is_logged_and_the_node_exits(self):
        self.set("relays/pump", True)
        self.set("pwm_board/out0", True)
        self.sim.silence(RELAYS, True)
        try:
            t0 = time.time()
            code = self.stop_node(signal.SIGINT)
            took = time.time() - t0
        finally:
            self.sim.silence(RELAYS, False)
        self.assertEqual(code, 0)
        self.assertLess(took, self.config["shutdown_timeout"] + 10, "bounded")
        self.assertIn("relays: fail-safe shutdown (node stops)", self.node.output)
        self.assertIn("NOT confirmed", self.node.output)
        self.assertEqual(self.coils(RELAYS, 1), [1], "the silent board kept its state")
        # The other boards still got theirs.
        self.assertEqual(self.coils(PWM, 2), [0, 1])
        self.start_node()

    def test_7_restore_keeps_what_the_fail_safe_set_while_the_heartbeat_is_lost(self):
        # Issue #24 items 1, 2 and 7. on_start: safe writes pump off, valve off, lamp on; the
        # user turns pump and fan on; the heartbeat is lost (pump off, lamp on); the board is
        # power-cycled. The restore must write the last confirmed states with the held
        # channels safe: pump stays off with no heartbeat, lamp (on only by the fail-safe) and
        # fan (the user's) come back on.
        if not self.node.running:
            self.start_node()
        self.set("relays/pump", True)
        self.set("relays/fan", True)
        since = len(self.events)
        self.beating.clear()
        try:
            helpers.wait_until(lambda: self.coils(RELAYS, 4) == [0, 0, 1, 1], 5, "relays safe")
            self.event("heartbeat", "relays", since)
            self.event("heartbeat", "pwm_board", since)
            # A late subscriber sees each device's newest event (the bus-wide topic keeps one).
            for device in ("relays", "pwm_board"):
                late = helpers.Latest(NS + device + "/failsafe", FailsafeEvent)
                e = late.wait(10, what="%s's latched fail-safe event" % device)
                self.assertEqual((e.device, e.trigger), (device, "heartbeat"))
            since = len(self.events)
            self.sim.command("power_cycle")  # every output off
            e = self.event("restart", "relays", since)
            self.assertEqual(e.action, "restore")
            self.assertTrue(e.confirmed, e.message)
            helpers.wait_until(lambda: self.coils(RELAYS, 4) == [0, 0, 1, 1], 10,
                               "pump held off, lamp and fan restored")
            self.assertEqual(dict(zip(e.channels, e.states))["pump"], False)
            status = helpers.device_status(self.diag, "relays")
            self.assertEqual(status.level, DiagnosticStatus.WARN, status)
            self.assertIn("safe state", status.message)
        finally:
            self.beating.set()
        # A new command ends the hold: the next restore writes the user's state.
        self.set("relays/pump", True)
        since = len(self.events)
        self.sim.command("power_cycle")
        self.event("restart", "relays", since)
        helpers.wait_until(lambda: self.coils(RELAYS, 4) == [1, 0, 1, 1], 10, "pump restored")

    def test_8_a_share_clients_write_is_a_command_not_a_restart(self):
        # Issue #24 item 3: a write through the share is confirmed by the board's reply; the
        # next poll must not take it for a power cycle (nothing reverted, nothing counted), and
        # a later restore writes it again.
        self.stop_node(signal.SIGINT)
        port = helpers.free_port()
        self.config["share"] = {"listen": "127.0.0.1:%d" % port, "allow": ["127.0.0.1"]}
        try:
            self.start_node()
            self.set("relays/fan", False)
            restarts = helpers.device_value(self.diag, "relays", "restarts detected")
            since = len(self.events)
            self.assertEqual(helpers.modbus_tcp_write_coil(port, int(RELAYS), 3, True), "ok")
            self.assertEqual(self.coils(RELAYS, 4)[3], 1)
            # Enough polls (10 Hz) for a restart to have been seen.
            outputs = helpers.Latest(NS + "relays/outputs", DigitalStates)
            helpers.wait_until(lambda: outputs.count >= 6, 10, "5 more polls of the relays")
            self.assertEqual(self.coils(RELAYS, 4)[3], 1, "the share's write was reverted")
            self.assertFalse([e for e in self.events[since:] if e.trigger == "restart"])
            self.assertEqual(helpers.device_value(self.diag, "relays", "restarts detected"),
                             restarts)
            self.sim.command("power_cycle")
            self.event("restart", "relays", since)
            helpers.wait_until(lambda: self.coils(RELAYS, 4)[3] == 1, 10, "fan restored")
        finally:
            del self.config["share"]

    def test_9_the_stated_safe_time_holds_on_a_bus_with_a_silent_device(self):
        # Issue 48: each device with a trigger states at start how long its outputs may take to
        # be safe after its last heartbeat or command (docs/failsafe.md, "How long until safe"),
        # in the log and in /diagnostics. With the PDU silent (its polls cost every retry) the
        # heartbeat is lost: both boards are safe within what they stated.
        if not self.node.running:
            self.start_node()
        stated = {}
        for device in ("relays", "pwm_board"):
            stated[device] = float(helpers.device_value(self.diag, device, "safe within [s]"))
            self.assertIn("%s: safe within %.3f s of its last heartbeat" % (device, stated[device]),
                          self.node.output)
        self.assertNotIn("pdu: safe within", self.node.output, "every socket holds: no safe time")
        self.set("relays/pump", True)
        self.set("pwm_board/out1", False)
        self.sim.silence("2", True)
        try:
            time.sleep(1.0)  # the PDU's polls fail (retries, then backoff) from here
            self.beating.clear()
            t0 = time.time()
            # The last heartbeat went out at most one beat (0.05 s) before t0.
            for device, dev, safe in (("relays", RELAYS, [0, 0, 1]), ("pwm_board", PWM, [0, 1])):
                helpers.wait_until(lambda: self.coils(dev, len(safe)) == safe,
                                   stated[device] + 5, device + " safe")
                took = time.time() - t0 + 0.05
                self.assertLessEqual(took, stated[device],
                                     "%s safe after %.3f s, stated %.3f s" %
                                     (device, took, stated[device]))
        finally:
            self.sim.silence("2", False)
            self.beating.set()


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "failsafe", FailsafeTest)
