#!/usr/bin/env python3
"""Yespeed PDU at address 2 through the bus node: telemetry follows the device, limits are
latched and set within the manual's rules, relays switch."""
import time
import unittest

import rospy
import rostest
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import PduLimits, PduTelemetry
from modbus_rtu_driver.srv import SetPduLimits

import helpers

NS = "/bus/pdu/"
PDU = "2"


class YespeedPduTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_yespeed_pdu")
        cls.sim = helpers.sim()
        cls.telemetry = helpers.Latest(NS + "telemetry", PduTelemetry)
        cls.telemetry.wait(20, what="the first telemetry message")

    def test_telemetry_is_plausible_and_stamped_at_read_time(self):
        msg = self.telemetry.wait(5)
        self.assertGreater(msg.voltage, 150.0)
        self.assertLess(msg.voltage, 300.0)
        self.assertGreater(msg.humidity, 0.0)
        self.assertLessEqual(msg.humidity, 100.0)
        age = (rospy.Time.now() - msg.header.stamp).to_sec()
        self.assertLess(abs(age), 5.0)
        first = self.telemetry.count
        helpers.wait_until(lambda: self.telemetry.count >= first + 3, 10, "telemetry every poll")

    def test_telemetry_follows_the_device(self):
        # Pin the device's voltage and temperature registers (-5.5 C is signed) and watch them.
        self.sim.set(PDU, "input_register", 0, 0x10000 - 55)
        self.sim.set(PDU, "input_register", 2, 2305)
        self.telemetry.wait(5, lambda m: abs(m.voltage - 230.5) < 0.01 and
                            abs(m.temperature + 5.5) < 0.01, "230.5 V and -5.5 C")

    def test_limits_latched_then_set(self):
        limits = rospy.wait_for_message(NS + "limits", PduLimits, timeout=10)
        self.assertAlmostEqual(limits.over_voltage, 250.0, places=3)
        self.assertAlmostEqual(limits.under_voltage, 200.0, places=3)
        self.assertAlmostEqual(limits.over_current, 16.0, places=3)
        set_limits = helpers.service(NS + "set_limits", SetPduLimits)
        res = set_limits(PduLimits(over_voltage=260.0, under_voltage=160.0, over_current=7.0))
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(PDU, "holding_register", 0, 3), [2600, 1600, 700])
        latest = helpers.Latest(NS + "limits", PduLimits)
        latest.wait(5, lambda m: abs(m.over_voltage - 260.0) < 0.01, "the new limits latched")

    def test_bad_limits_are_refused_and_nothing_is_written(self):
        before = self.sim.get(PDU, "holding_register", 0, 3)
        set_limits = helpers.service(NS + "set_limits", SetPduLimits)
        cases = [
            (PduLimits(over_voltage=170.0, under_voltage=160.0, over_current=10.0), "over_voltage"),
            (PduLimits(over_voltage=250.0, under_voltage=285.0, over_current=10.0), "under_voltage"),
            (PduLimits(over_voltage=250.0, under_voltage=200.0, over_current=5.0), "over_current"),
            (PduLimits(over_voltage=250.0, under_voltage=200.0, over_current=20.0), "over_current"),
        ]
        for limits, field in cases:
            res = set_limits(limits)
            self.assertFalse(res.success, limits)
            self.assertIn(field, res.message)
        time.sleep(0.2)
        self.assertEqual(self.sim.get(PDU, "holding_register", 0, 3), before)

    def test_limit_rules_hold_for_the_register_values_written(self):
        # Issue #13/6: 180.00001 V would be written as 1800 and 19.999999 A as 2000; both
        # break the rules on the device: refused by the node, nothing sent.
        before = self.sim.get(PDU, "holding_register", 0, 3)
        set_limits = helpers.service(NS + "set_limits", SetPduLimits)
        for limits, words in [
                (PduLimits(over_voltage=180.00001, under_voltage=160.0, over_current=10.0),
                 "over_voltage: 180.0 V (register 1800)"),
                (PduLimits(over_voltage=250.0, under_voltage=200.0, over_current=19.999999),
                 "over_current: 20.00 A (register 2000)")]:
            res = set_limits(limits)
            self.assertFalse(res.success, limits)
            self.assertIn(words, res.message)
        self.assertEqual(self.sim.get(PDU, "holding_register", 0, 3), before)

    def test_one_limit_alone_keeps_the_others(self):
        set_limits = helpers.service(NS + "set_limits", SetPduLimits)
        before = self.sim.get(PDU, "holding_register", 0, 3)
        target = 2550 if before[0] != 2550 else 2560
        res = set_limits(PduLimits(over_voltage=target / 10.0))
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(PDU, "holding_register", 0, 3), [target] + before[1:])
        latest = helpers.Latest(NS + "limits", PduLimits)
        latest.wait(5, lambda m: abs(m.over_voltage - target / 10.0) < 0.01, "the new limit")
        # The merged set must follow the rules: an under-voltage not below the device's own
        # over-voltage is refused, and nothing is written.
        res = set_limits(PduLimits(under_voltage=(target + 10) / 10.0))
        self.assertFalse(res.success)
        self.assertIn("must be above under_voltage", res.message)
        self.assertEqual(self.sim.get(PDU, "holding_register", 0, 3), [target] + before[1:])

    def test_relays(self):
        res = helpers.service(NS + "out1/set", SetBool)(True)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(PDU, "coil", 1, 1), [1])
        res = helpers.service(NS + "out1/set", SetBool)(False)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(PDU, "coil", 1, 1), [0])


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "yespeed_pdu", YespeedPduTest)
