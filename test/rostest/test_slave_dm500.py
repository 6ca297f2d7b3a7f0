#!/usr/bin/env python3
"""Slave role against the simulated DM500: the topics carry exactly what the master wrote, the
services set what it reads back, out-of-range requests get exception 02, and frames for other
ids or with bad CRCs never cost a valid request its answer (the master's script checks those).
The names are singular, as the YAML's tables; the plural names of earlier versions still work
for one release, and each warns once naming its new name (docs/ros_api.md)."""
import os
import time
import unittest

import rosgraph
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from rosgraph_msgs.msg import Log
from std_msgs.msg import Bool, UInt16

from modbus_rtu_driver.msg import WrittenCoils, WrittenRegisters
from modbus_rtu_driver.srv import SetBits, SetRegisters

import helpers

NS = "/cnc/"
# Old (plural) name -> the name that replaced it.
RENAMED = {NS + "written/coils": NS + "written/coil",
           NS + "written/holding_registers": NS + "written/holding_register",
           NS + "coils/spindle_ready": NS + "coil/spindle_ready",
           NS + "holding_registers/job_number": NS + "holding_register/job_number",
           NS + "set_coils": NS + "set_coil",
           NS + "set_discrete_inputs": NS + "set_discrete_input",
           NS + "set_holding_registers": NS + "set_holding_register",
           NS + "set_input_registers": NS + "set_input_register"}


def node_uri(name):
    try:
        return rosgraph.Master(rospy.get_name()).lookupNode(name)
    except rosgraph.MasterError:
        return None


def writes(messages):
    return [(m.address, list(getattr(m, "states", None) or getattr(m, "values"))) for m in messages]


class SlaveDm500Test(unittest.TestCase):
    def test_dm500_session(self):
        rospy.init_node("test_slave_dm500")
        # The warnings of the old names reach this test on /rosout: listen before using them.
        log = []
        rosout = rospy.Subscriber("/rosout", Log,
                                  lambda m: log.append(m.msg) if m.name == "/cnc" else None)
        cnc = helpers.wait_until(lambda: node_uri("/cnc"), 20, "the node /cnc")
        helpers.wait_until(lambda: rosout.impl.has_connection(cnc), 20, "/rosout from /cnc")
        coils, regs, old_coils, old_regs = [], [], [], []
        subs = [rospy.Subscriber(NS + "written/coil", WrittenCoils, coils.append),
                rospy.Subscriber(NS + "written/holding_register", WrittenRegisters, regs.append),
                rospy.Subscriber(NS + "written/coils", WrittenCoils, old_coils.append),
                rospy.Subscriber(NS + "written/holding_registers", WrittenRegisters,
                                 old_regs.append)]
        spindle = helpers.Latest(NS + "coil/spindle_ready", Bool)
        job = helpers.Latest(NS + "holding_register/job_number", UInt16)
        old_spindle = helpers.Latest(NS + "coils/spindle_ready", Bool)
        old_job = helpers.Latest(NS + "holding_registers/job_number", UInt16)
        set_coils = helpers.service(NS + "set_coil", SetBits)
        set_inputs = helpers.service(NS + "set_discrete_input", SetBits)
        set_holding = helpers.service(NS + "set_holding_register", SetRegisters)
        set_input_regs = helpers.service(NS + "set_input_register", SetRegisters)

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

        # The old names: the same messages, and services that set the same tables.
        helpers.wait_until(lambda: writes(old_coils) == writes(coils) and
                           writes(old_regs) == writes(regs), 10,
                           "the same writes on the old topics (%s, %s)"
                           % (writes(old_coils), writes(old_regs)))
        self.assertTrue(old_spindle.wait(5, lambda m: m.data, "old spindle_ready true").data)
        self.assertEqual(old_job.wait(5, lambda m: m.data == 0x0807, "old job_number").data,
                         0x0807)
        for name, srv_type, values in (("set_coils", SetBits, [True]),
                                       ("set_discrete_inputs", SetBits, [True]),
                                       ("set_holding_registers", SetRegisters, [7]),
                                       ("set_input_registers", SetRegisters, [7])):
            old = helpers.service(NS + name, srv_type)
            for _ in range(2):
                res = old(address=60, values=values)
                self.assertTrue(res.success, res.message)
        res = helpers.service(NS + "set_coils", SetBits)(address=64, values=[True])
        self.assertFalse(res.success)  # the same checks as the new name
        self.assertIn("coil 0-63", res.message)

        # Each old name warned once, naming its new name; the new names never warn.
        def warned(old):
            return [m for m in log
                    if m == "%s is deprecated, use %s; removed in the next release"
                    % (old, RENAMED[old])]
        helpers.wait_until(lambda: all(warned(old) for old in RENAMED), 10,
                           "a warning for each old name (got: %s)" % log)
        for old in RENAMED:
            self.assertEqual(len(warned(old)), 1, "%s: %s" % (old, log))
        self.assertEqual(len([m for m in log if "deprecated" in m]), len(RENAMED), log)
        rosout.unregister()

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
