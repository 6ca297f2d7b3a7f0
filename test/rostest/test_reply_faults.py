#!/usr/bin/env python3
"""Spoilt replies against the real node and the simulator over a real pty. Every service call
must get its true outcome (checked in the simulator's registers), a late reply must never be
read as the answer to another request, a slow device must work, and a share of lost requests
and replies must neither lose a call's outcome nor make the board do something twice."""
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import DigitalStates, PwmStates
from modbus_rtu_driver.srv import SetPwm, StopPwm

import helpers

NS = "/bus/"
RELAYS, PWM, SLOW = "8", "1", "3"


class ReplyFaultsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_reply_faults")
        cls.sim = helpers.sim()
        cls.bus_values = {}
        cls.bus_level = None
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diag)
        cls.inputs = helpers.Latest(NS + "relays/inputs", DigitalStates)
        cls.pwm = helpers.Latest(NS + "pwm_board/pwm", PwmStates)
        cls.inputs.wait(30, what="relay board polls")
        cls.pwm.wait(30, what="pwm board polls")
        cls.valve = helpers.service(NS + "relays/valve/set", SetBool)
        cls.lamp = helpers.service(NS + "relays/lamp/set", SetBool)
        cls.set_pwm = helpers.service(NS + "pwm_board/set_pwm", SetPwm)

    @classmethod
    def on_diag(cls, msg):
        for s in msg.status:
            if s.name.split(": ", 1)[-1].startswith("bus "):
                cls.bus_values = {kv.key: kv.value for kv in s.values}
                cls.bus_level = (s.level, s.message)

    def counter(self, key):
        helpers.wait_until(lambda: key in self.bus_values, 10, "bus diagnostics with " + key)
        return int(self.bus_values[key])

    def counter_grows(self, key, before):
        helpers.wait_until(lambda: self.counter(key) > before, 10, "%s above %d" % (key, before))

    def set_and_check(self, proxy, channel, state):
        """One call; its answer must be what the board shows."""
        res = proxy(state)
        coil = self.sim.get(RELAYS, "coil", channel)[0]
        if res.success:
            self.assertEqual(coil, int(state), "success reported, board shows %d: %s" %
                             (coil, res.message))
        else:
            self.assertIn("not", res.message, "a failure must say what is known")
        return res

    def test_1_spoilt_replies_are_survived_and_counted(self):
        # kind -> the bus counter it must raise
        kinds = [("corrupt", "crc errors", 0), ("truncate", "timeouts", 0),
                 ("wrong_address", "wrong address", 0), ("noise", "stale bytes", 0),
                 ("late", "stale bytes", 120)]  # 120 ms: after the timeout (~62 ms), within the guard
        for kind, key, late_ms in kinds:
            before = self.counter(key)
            self.sim.spoil(kind, RELAYS, 2, late_ms)
            for i in range(6):
                res = self.set_and_check(self.valve, 1, i % 2 == 0)
                self.assertTrue(res.success, "%s: %s" % (kind, res.message))
            self.counter_grows(key, before)
            # Still polled correctly afterwards: an input set on the board shows.
            self.sim.set(RELAYS, "discrete_input", 5, 1)
            self.inputs.wait(5, lambda m: m.states[5], "input 5 on after %s" % kind)
            self.sim.set(RELAYS, "discrete_input", 5, 0)
            self.inputs.wait(5, lambda m: not m.states[5], "input 5 off after %s" % kind)

    def test_2_a_late_reply_of_the_same_shape_is_never_read_for_another_channel(self):
        # Each stopped channel gets its own period (1.0 + 0.1 k s): a reply read for the wrong
        # channel would show another channel's period in the topic.
        for ch in range(6):
            self.sim.set(PWM, "holding_register", ch * 16, 10 + ch, ch, 0)
        expected = [1.0 + 0.1 * ch for ch in range(6)]
        self.pwm.wait(10, lambda m: all(abs(m.channels[c].period - expected[c]) < 1e-6
                                        for c in range(6)), "every channel's own period")
        retries, ok = self.counter("retries"), self.counter("ok")
        seen = []  # the topic is published when something changes: a misread would show
        sub = rospy.Subscriber(NS + "pwm_board/pwm", PwmStates, seen.append)
        stop = helpers.service(NS + "pwm_board/stop_pwm", StopPwm)
        for _ in range(4):
            # Every reply late, then a stop: the node reads all 8 channels back to back, the
            # same request shape 8 times in a row.
            self.sim.spoil("late", PWM, 10, 90)  # between one and two timeouts (~62 ms)
            stop(channel=7)
            time.sleep(1.0)
        sub.unregister()
        for m in seen:
            for c in range(6):
                self.assertAlmostEqual(m.channels[c].period, expected[c], 6,
                                       "channel %d shows %.1f s" % (c, m.channels[c].period))
        self.counter_grows("retries", retries)  # the late replies did come late
        # /diagnostics comes once a second: wait for the count rather than read it once.
        helpers.wait_until(lambda: self.counter("ok") - ok > 40, 10,
                           "the bus to have kept polling (over 40 transactions ok)")

    def test_3_a_device_with_a_1000_ms_return_delay_works(self):
        self.sim.set(SLOW, "holding_register", 0x00FC, 25)  # 25 x 40 ms
        try:
            out0 = helpers.service(NS + "slow_board/out0/set", SetBool)
            t0 = time.time()
            res = out0(True)
            took = time.time() - t0
            self.assertTrue(res.success, res.message)
            self.assertEqual(self.sim.get(SLOW, "coil", 0), [1])
            self.assertGreater(took, 0.9, "the board waited its return delay")
            res = out0(False)
            self.assertTrue(res.success, res.message)
            self.assertEqual(self.sim.get(SLOW, "coil", 0), [0])
            # The other boards are still polled meanwhile.
            # (a poll of the slow board holds the line 2 s, every 10 s)
            count = self.inputs.count
            time.sleep(4.0)
            self.assertGreater(self.inputs.count - count, 3)
            print("slow device: SetBool answered in %.2f s; relay inputs %.1f Hz meanwhile" %
                  (took, (self.inputs.count - count) / 4.0))
        finally:
            self.sim.set(SLOW, "holding_register", 0x00FC, 0)

    def test_4_lost_requests_and_replies_give_true_outcomes_and_no_double_action(self):
        self.sim.drop(RELAYS, 10, "reply")
        self.sim.drop(RELAYS, 5, "request")
        self.sim.drop(PWM, 15, "reply")
        self.sim.drop(PWM, 5, "request")
        try:
            # Relays: every answer is checked against the board; every change on the board is
            # one the caller asked for.
            relay_changes = self.sim.stats(RELAYS)["changes"]
            changed = ok = 0
            state = self.sim.get(RELAYS, "coil", 2)[0]
            for i in range(100):
                want = i % 2 == 0
                res = self.set_and_check(self.lamp, 2, want)
                now = self.sim.get(RELAYS, "coil", 2)[0]
                changed += now != state
                ok += res.success
                if not res.success and "not done" in res.message:
                    self.assertEqual(now, state, res.message)
                state = now
            self.assertEqual(self.sim.stats(RELAYS)["changes"] - relay_changes, changed)
            self.assertGreaterEqual(ok, 90)
            # PWM bursts: a write is never sent twice, so the board never starts more runs than
            # it was asked for, and every success is a run the board really has.
            pwm_starts = self.sim.stats(PWM)["changes"]
            calls = pwm_ok = 0
            for i in range(40):
                ch = i % 6
                res = self.set_pwm(channel=ch, period=20.0 + i, on_time=10.0, pulses=5)
                calls += 1
                if res.success:
                    pwm_ok += 1
                    regs = self.sim.get(PWM, "holding_register", ch * 16, 3)
                    self.assertEqual(regs[:2], [200 + 10 * i, 100], res.message)
                    self.assertGreater(regs[2], 0, res.message)
            starts = self.sim.stats(PWM)["changes"] - pwm_starts
            self.assertLessEqual(starts, calls, "a burst was started twice")
            self.assertLessEqual(pwm_ok, starts)
            relay_stats, pwm_stats = self.sim.stats(RELAYS), self.sim.stats(PWM)
            print("drops: relays 100 calls, %d succeeded, %d changes; dropped requests %d, "
                  "replies %d" % (ok, changed, relay_stats["dropped_requests"],
                                  relay_stats["dropped_replies"]))
            print("drops: pwm 40 bursts asked, %d succeeded, %d started; dropped requests %d, "
                  "replies %d" % (pwm_ok, starts, pwm_stats["dropped_requests"],
                                  pwm_stats["dropped_replies"]))
            self.assertGreater(relay_stats["dropped_replies"] + pwm_stats["dropped_replies"], 0)
        finally:
            for dev in (RELAYS, PWM):
                self.sim.drop(dev, 0, "reply")
                self.sim.drop(dev, 0, "request")
            for ch in range(6):
                self.sim.set(PWM, "holding_register", ch * 16 + 2, 0)

    def test_5_the_bus_level_says_how_the_line_is_now(self):
        """WARN while failed attempts are recent (also those a retry made good), OK again once
        the line has been clean for the window (10 s); the totals stay."""
        before = self.counter("crc errors")
        self.sim.spoil("corrupt", RELAYS, 1)
        self.assertTrue(self.valve(True).success)  # the retry gets through
        self.counter_grows("crc errors", before)
        helpers.wait_until(lambda: self.bus_level and self.bus_level[0] == DiagnosticStatus.WARN, 10,
                           "bus WARN after a failed attempt")
        self.assertIn("failed attempt", self.bus_level[1])
        helpers.wait_until(lambda: self.bus_level[0] == DiagnosticStatus.OK, 40,
                           "bus OK again once the line is clean")
        self.assertGreater(self.counter("crc errors"), before)


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "reply_faults", ReplyFaultsTest)
