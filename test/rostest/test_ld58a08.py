#!/usr/bin/env python3
"""LD58A08 at address 1 through the bus node: outputs and PWM services change the simulated
board's registers as the manual says; a pulse burst that ends on the board shows in the topics."""
import time
import unittest

import rospy
import rostest
from std_msgs.msg import Bool
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import DigitalStates, PwmStates
from modbus_rtu_driver.srv import SetOutputs, SetPwm, StopPwm

import helpers

NS = "/bus/pwm_board/"
BOARD = "1"


class Ld58a08Test(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_ld58a08")
        cls.sim = helpers.sim()
        cls.outputs = helpers.Latest(NS + "outputs", DigitalStates)
        cls.pwm = helpers.Latest(NS + "pwm", PwmStates)
        cls.outputs.wait(20, what="the first outputs message")
        cls.set_pwm = helpers.service(NS + "set_pwm", SetPwm)
        cls.stop_pwm = helpers.service(NS + "stop_pwm", StopPwm)

    def regs(self, address, count):
        return self.sim.get(BOARD, "holding_register", address, count)

    def test_set_bool_and_mask_register_agree(self):
        res = helpers.service(NS + "out4/set", SetBool)(True)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(BOARD, "coil", 4, 1), [1])
        self.assertTrue(self.regs(0x80, 1)[0] & (1 << 4), "0x0080 mirrors the coils")
        self.outputs.wait(5, lambda m: m.states[4], "out4 on in outputs")
        res = helpers.service(NS + "out4/set", SetBool)(False)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(BOARD, "coil", 4, 1), [0])

    def test_set_outputs(self):
        set_outputs = helpers.service(NS + "set_outputs", SetOutputs)
        res = set_outputs(channels=[2, 3], states=[True, True])
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(BOARD, "coil", 2, 2), [1, 1])
        res = set_outputs(channels=[2, 3], states=[False, False])
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(BOARD, "coil", 2, 2), [0, 0])

    def test_slow_pwm_burst_runs_and_ends(self):
        res = self.set_pwm(channel=0, period=0.2, on_time=0.1, pulses=4)
        self.assertTrue(res.success, res.message)
        period, on_time, _ = self.regs(0x00, 3)
        self.assertEqual((period, on_time), (2, 1), "0.2 s and 0.1 s in units of 0.1 s")
        self.pwm.wait(5, lambda m: m.channels[0].period > 0.19, "channel 0 period in pwm")
        # 4 pulses of 0.2 s: the board stops by itself and clears the pulse register.
        helpers.wait_until(lambda: self.regs(0x02, 1) == [0], 10, "the burst to end on the board")
        self.pwm.wait(5, lambda m: not m.channels[0].running, "pwm to show channel 0 stopped")
        self.assertEqual(self.sim.get(BOARD, "coil", 0, 1), [0])

    def test_slow_pwm_continuous(self):
        res = self.set_pwm(channel=3, period=50.0, on_time=20.0, pulses=0)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.regs(0x30, 3), [500, 200, 0xFFFF])
        # pulses: 0 (continuous) reads back as continuous, not as 65535 pulses left.
        self.pwm.wait(5, lambda m: m.channels[3].running and m.channels[3].continuous and
                      m.channels[3].remaining_pulses == 0, "channel 3 running continuously")
        res = self.stop_pwm(channel=3)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.regs(0x32, 1), [0])

    def test_fast_pwm_registers(self):
        res = self.set_pwm(channel=6, frequency=10000, duty_cycle=30, duration=100.0)
        self.assertTrue(res.success, res.message)
        freq, duty, _ = self.regs(0x60, 3)
        self.assertEqual((freq, duty), (10000, 30))
        self.pwm.wait(5, lambda m: m.channels[6].frequency == 10000 and m.channels[6].running,
                      "channel 6 at 10 kHz")
        res = self.stop_pwm(channel=6)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.regs(0x62, 1), [0])
        self.pwm.wait(5, lambda m: not m.channels[6].running, "channel 6 stopped")

    def test_outputs_on_running_pwm_channels_stop_the_pwm_first(self):
        # Manual, 0x0080: an output applies only while the channel's enable register is 0.
        res = self.set_pwm(channel=5, period=1.0, on_time=0.5, pulses=0)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.regs(0x52, 1), [0xFFFF])
        res = helpers.service(NS + "out5/set", SetBool)(True)
        self.assertTrue(res.success, res.message)
        self.assertEqual(res.message, "out5 on (PWM on channel 5 stopped first)")
        self.assertEqual(self.regs(0x52, 1), [0], "enable register 0")
        self.assertEqual(self.sim.get(BOARD, "coil", 5, 1), [1])
        time.sleep(1.2)  # over one PWM period: a PWM still running would have switched it off
        self.assertEqual(self.sim.get(BOARD, "coil", 5, 1), [1], "a plain output now")
        self.pwm.wait(5, lambda m: not m.channels[5].running, "pwm to show channel 5 stopped")
        # set_outputs: only the running channel is stopped, both are written.
        res = self.set_pwm(channel=6, frequency=1000, duty_cycle=50, duration=0)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(BOARD, "coil", 6, 1), [1], "the PWM drives output 6")
        set_outputs = helpers.service(NS + "set_outputs", SetOutputs)
        res = set_outputs(channels=[6, 7], states=[False, True])
        self.assertTrue(res.success, res.message)
        self.assertIn("PWM on channel 6 stopped first", res.message)
        self.assertEqual(self.regs(0x62, 1), [0])
        self.assertEqual(self.sim.get(BOARD, "coil", 6, 2), [0, 1])
        # The command topic (fire and forget) does the same.
        res = self.set_pwm(channel=1, period=0.4, on_time=0.2, pulses=0)
        self.assertTrue(res.success, res.message)
        pub = rospy.Publisher(NS + "out1/command", Bool, queue_size=1, latch=True)
        pub.publish(Bool(True))
        helpers.wait_until(lambda: self.regs(0x12, 1) == [0], 10, "PWM 1 stopped by out1/command")
        helpers.wait_until(lambda: self.sim.get(BOARD, "coil", 1, 1) == [1], 10, "out1 on")
        time.sleep(0.5)  # over one PWM period
        self.assertEqual(self.sim.get(BOARD, "coil", 1, 1), [1])
        pub.unregister()
        res = set_outputs(channels=[1, 5, 7], states=[False, False, False])
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(BOARD, "coil", 0, 8)[5:8], [0, 0, 0])

    def test_pwm_messages_say_the_real_problem(self):
        cases = [
            (dict(channel=7, frequency=1000, duty_cycle=33.3), "not a whole percent"),
            (dict(channel=2, period=1.0, on_time=0.55), "not a multiple of the 0.1 s step"),
            (dict(channel=1, frequency=1000, duty_cycle=50),
             "channel 1 takes period/on_time/pulses (channels 0-5); "
             "frequency/duty_cycle/duration are for channels 6-7"),
        ]
        for args, words in cases:
            res = self.set_pwm(**args)
            self.assertFalse(res.success, args)
            self.assertIn(words, res.message, args)

    def test_fast_pwm_output_time_ends(self):
        res = self.set_pwm(channel=7, frequency=2000, duty_cycle=55, duration=0.5)
        self.assertTrue(res.success, res.message)
        helpers.wait_until(lambda: self.regs(0x72, 1) == [0], 10, "the output time to run out")
        self.pwm.wait(5, lambda m: not m.channels[7].running, "channel 7 stopped in pwm")

    def test_bad_pwm_values_are_refused_and_nothing_is_written(self):
        before = self.regs(0x10, 3) + self.regs(0x70, 3)
        cases = [
            (dict(channel=1, period=0.05, on_time=0.0), ["period", "0.1", "6553.5"]),
            (dict(channel=1, period=1.0, on_time=2.0), ["on_time", "period"]),
            (dict(channel=7, frequency=30000, duty_cycle=50), ["frequency", "1", "20000"]),
            (dict(channel=7, frequency=100, duty_cycle=101), ["duty_cycle", "100"]),
            (dict(channel=8, period=1.0, on_time=0.5), ["channel", "0", "7"]),
        ]
        for args, words in cases:
            res = self.set_pwm(**args)
            self.assertFalse(res.success, args)
            for w in words:
                self.assertIn(w, res.message, args)
        res = self.stop_pwm(channel=9)
        self.assertFalse(res.success)
        self.assertIn("channel", res.message)
        time.sleep(0.2)
        self.assertEqual(self.regs(0x10, 3) + self.regs(0x70, 3), before)


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "ld58a08", Ld58a08Test)
