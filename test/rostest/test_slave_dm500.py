#!/usr/bin/env python3
"""Slave role against the simulated DM500: the topics carry exactly what the master wrote, the
services set what it reads back, out-of-range requests get exception 02, and frames for other
ids or with bad CRCs never cost a valid request its answer (the master's script checks those)."""
import os
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from std_msgs.msg import Bool, UInt16

from modbus_rtu_driver.msg import WrittenCoils, WrittenRegisters
from modbus_rtu_driver.srv import SetBits, SetRegisters

import helpers

NS = "/cnc/"


class SlaveDm500Test(unittest.TestCase):
    def test_dm500_session(self):
        rospy.init_node("test_slave_dm500")
        coils, regs = [], []
        subs = [rospy.Subscriber(NS + "written/coils", WrittenCoils, coils.append),
                rospy.Subscriber(NS + "written/holding_registers", WrittenRegisters, regs.append)]
        spindle = helpers.Latest(NS + "coils/spindle_ready", Bool)
        job = helpers.Latest(NS + "holding_registers/job_number", UInt16)
        set_coils = helpers.service(NS + "set_coils", SetBits)
        set_inputs = helpers.service(NS + "set_discrete_inputs", SetBits)
        set_holding = helpers.service(NS + "set_holding_registers", SetRegisters)
        set_input_regs = helpers.service(NS + "set_input_registers", SetRegisters)

        # Tell the master to start once the subscriptions are connected.
        helpers.wait_until(lambda: rospy.get_published_topics() and
                           all(sub.get_num_connections() > 0 for sub in subs), 20,
                           "subscriptions to connect")
        res = set_holding(address=63, values=[1])
        self.assertTrue(res.success, res.message)
        # The master's signal: it wrote 1 to register 30.
        helpers.wait_until(lambda: any(m.address == 30 for m in regs), 60, "the master's signal")
        first_coils = coils[0]
        self.assertEqual(first_coils.address, 6)
        self.assertEqual(list(first_coils.states),
                         [True, True, False, False, False, False, False, False, False, False, True, False])
        first_regs = regs[0]
        self.assertEqual(first_regs.address, 5)
        self.assertEqual(list(first_regs.values), [0x0807, 0x0A09])
        self.assertEqual(list(bytearray(first_regs.bytes)), [7, 8, 9, 10])
        broadcast = [m for m in regs if m.address == 20]
        self.assertEqual(len(broadcast), 1)
        self.assertEqual(list(broadcast[0].values), [4242])
        # Each write is published once: no write from the refused requests.
        self.assertEqual([m.address for m in regs], [5, 20, 30])
        self.assertTrue(spindle.wait(5, lambda m: m.data, "spindle_ready true").data)
        self.assertEqual(job.wait(5, lambda m: m.data == 0x0807, "job_number").data, 0x0807)

        # Out of range: refused with a message, nothing set.
        res = set_holding(address=64, values=[1])
        self.assertFalse(res.success)
        self.assertIn("address", res.message)
        self.assertIn("holding_register 0-63", res.message)
        res = set_coils(address=63, values=[True, True])
        self.assertFalse(res.success)
        # What the master reads next.
        for call, kwargs in ((set_inputs, dict(address=0, values=[True, False, True, True])),
                             (set_input_regs, dict(address=10, values=[500, 600])),
                             (set_coils, dict(address=50, values=[False, True])),
                             (set_holding, dict(address=40, values=[111, 222]))):
            res = call(**kwargs)
            self.assertTrue(res.success, res.message)

        report_path = rospy.get_param("~report")
        helpers.wait_until(lambda: os.path.exists(report_path), 60, "the master's report")
        with open(report_path) as f:
            report = f.read()
        self.assertIn(" 0 failed", report, report)
        self.assertNotIn("FAIL", report, report)

        # The server counts a request after it has written the reply, and /diagnostics comes
        # once a second: the first message after the report may predate the last counts. Read
        # it until the counts are there (bounded), then check them.
        minimums = {"requests served": 15, "exceptions sent": 3, "crc errors": 1,
                    "frames for other ids": 2, "broadcasts": 1}

        def slave_values():
            m = rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=5)
            status = next((s for s in m.status if "slave 1" in s.name), None)
            return {kv.key: int(kv.value) for kv in status.values
                    if kv.key in minimums} if status else None
        values = helpers.wait_until(slave_values, 15, "slave diagnostics")
        deadline = time.time() + 15
        while time.time() < deadline and any(values.get(k, 0) < n for k, n in minimums.items()):
            values = helpers.wait_until(slave_values, 15, "slave diagnostics")
        self.assertGreaterEqual(values["requests served"], 15)
        self.assertGreaterEqual(values["exceptions sent"], 3)
        self.assertGreaterEqual(values["crc errors"], 1)
        self.assertGreaterEqual(values["frames for other ids"], 2)
        self.assertGreaterEqual(values["broadcasts"], 1)


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "slave_dm500", SlaveDm500Test)
