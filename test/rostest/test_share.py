#!/usr/bin/env python3
"""The node's Modbus TCP share against mbpoll (an independent libmodbus client) while the node
polls the simulator: writes through the share land in the simulated device and in the node's
state at the next poll; reads through it equal the simulator's registers and the node's topics;
bus failures and device refusals come back as Modbus exceptions; /diagnostics counts requests
per client; modbus_rtu_commission's scan through it lists exactly the devices. Also the
simulator's own Modbus TCP side (--tcp)."""
import json
import os
import re
import subprocess
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray

from modbus_rtu_driver.msg import DigitalStates
from modbus_rtu_driver.srv import SetOutputs

import helpers
from sim_control import SimControl

NS = "/bus/"
BOARD = "8"  # the LC relay board
PDU = "2"


def mbpoll(port, unit, table, ref, *values, count=1):
    """Runs mbpoll once (PDU addressing: -0); returns (exit code, output, values read)."""
    cmd = ["mbpoll", "-m", "tcp", "-p", str(port), "-a", str(unit), "-t", table, "-r", str(ref),
           "-0", "-1", "-o", "3"] + ([] if values else ["-c", str(count)]) + ["127.0.0.1"]
    cmd += [str(v) for v in values]  # writing: as many as given
    out = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=30,
                         check=False)
    text = out.stdout.decode(errors="replace")
    read = [int(v) for v in re.findall(r"^\[\d+\]:\s+(-?\d+)", text, re.M)]
    return out.returncode, text, read


class ShareTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_share", anonymous=True)
        cls.sim = helpers.sim()
        cls.port = rospy.get_param("~share_port")
        cls.outputs = helpers.Latest(NS + "relays/outputs", DigitalStates)
        cls.outputs.wait(20, what="the first outputs message")
        cls.diagnostics = helpers.Latest("/diagnostics", DiagnosticArray)
        # The share listens once the node has started its devices.
        helpers.wait_until(lambda: mbpoll(cls.port, BOARD, "0", 0)[0] == 0, 20,
                           "the share to answer")

    def test_a_write_through_the_share_lands_in_the_device_and_in_ros(self):
        for state in (1, 0):
            code, text, _ = mbpoll(self.port, BOARD, "0", 2, state)
            self.assertEqual(code, 0, text)
            self.assertEqual(self.sim.get(BOARD, "coil", 2), [state])
            self.outputs.wait(5, lambda m, s=state: m.states[2] == bool(s),
                              "lamp %d in outputs at the next poll" % state)

    def test_reads_through_the_share_are_true_on_both_sides(self):
        set_outputs = helpers.service(NS + "relays/set_outputs", SetOutputs)
        res = set_outputs(channels=[0, 3], states=[True, True])
        self.assertTrue(res.success, res.message)
        self.outputs.wait(5, lambda m: m.states[0] and m.states[3], "relays 0 and 3 on")
        code, text, coils = mbpoll(self.port, BOARD, "0", 0, count=8)
        self.assertEqual(code, 0, text)
        self.assertEqual(coils, self.sim.get(BOARD, "coil", 0, 8))
        self.assertEqual(coils, [int(s) for s in self.outputs.msg.states])
        code, text, limits = mbpoll(self.port, PDU, "4", 0, count=3)
        self.assertEqual(code, 0, text)
        self.assertEqual(limits, self.sim.get(PDU, "holding_register", 0, 3))
        res = set_outputs(channels=[0, 3], states=[False, False])
        self.assertTrue(res.success, res.message)

    def test_failures_come_back_as_exceptions(self):
        # Nobody at 77: the gateway's "target device failed to respond" (0B).
        code, text, _ = mbpoll(self.port, 77, "4", 0)
        self.assertNotEqual(code, 0, text)
        self.assertIn("Target device failed to respond", text)
        # The PDU refuses an over-voltage limit below 180 V: its own exception passes through.
        before = self.sim.get(PDU, "holding_register", 0)
        code, text, _ = mbpoll(self.port, PDU, "4", 0, 1000)
        self.assertNotEqual(code, 0, text)
        self.assertIn("Illegal data value", text)
        self.assertEqual(self.sim.get(PDU, "holding_register", 0), before)

    def test_the_commissioning_tools_scan_through_the_share_lists_only_the_devices(self):
        # Issue 32 item 16: the share answers 0B for an empty address after the node's own
        # timeouts (0.3 s x 2 here). That is no device, and the scan must wait for it: given up
        # sooner, the next addresses queue behind it in the share and a device is missed.
        tool = subprocess.check_output(["catkin_find", "--first-only", "--libexec",
                                        "modbus_rtu_driver", "modbus_rtu_commission"],
                                       text=True).strip()
        port = "tcp://127.0.0.1:%d" % self.port
        expected = [(1, "ld58a08"), (2, "yespeed_pdu"), (8, "lc_relay8")]
        for timeout in ([], ["--timeout", "1.5"]):  # the default, and one above the node's
            p = subprocess.run([tool, "--port", port] + timeout +
                               ["--json", "scan", "--addresses", "1-3,7-9"],
                               capture_output=True, text=True, timeout=120, check=False)
            result = json.loads(p.stdout)
            self.assertTrue(result["complete"], p.stdout + p.stderr)
            self.assertEqual([(d["address"], d["type"]) for d in result["devices"]], expected,
                             "%s: %s%s" % (timeout, p.stdout, p.stderr))
            self.assertEqual(p.returncode, 0, p.stderr)

    def test_diagnostics_count_requests_per_client(self):
        code, text, _ = mbpoll(self.port, BOARD, "1", 0, count=8)
        self.assertEqual(code, 0, text)

        def requests():
            for status in (self.diagnostics.msg.status if self.diagnostics.msg else []):
                if status.name.endswith("share"):
                    for kv in status.values:
                        if kv.key == "requests from 127.0.0.1":
                            return int(kv.value)
            return None
        self.assertGreater(helpers.wait_until(requests, 10, "the share in /diagnostics"), 0)

    def test_diagnostics_state_the_answer_bound(self):
        # docs/share.md, "How long an answer takes": the bound the node computed (twice the
        # longest transaction: bus_three.yaml's 0.3 s response timeout with one retry, so at
        # least 1.2 s), and the requests answered 0B at it (none on a quiet bus).
        def share_values():
            for status in (self.diagnostics.msg.status if self.diagnostics.msg else []):
                if status.name.endswith("share"):
                    return {kv.key: kv.value for kv in status.values}
            return None
        values = helpers.wait_until(share_values, 10, "the share in /diagnostics")
        bound = float(values["answer bound [s]"])
        self.assertGreaterEqual(bound, 1.2, values)
        self.assertLess(bound, 10.0, values)
        self.assertEqual(values["answered 0B at the bound (unsent)"], "0", values)

    def test_the_simulator_serves_its_devices_over_tcp(self):
        sim_port = rospy.get_param("~sim_port")
        tcp_sim = SimControl(rospy.get_param("~tcp_sim_control"))
        helpers.wait_until(lambda: os.path.exists(tcp_sim.path), 20, "the second simulator")
        helpers.wait_until(lambda: mbpoll(sim_port, BOARD, "0", 0)[0] == 0, 20,
                           "the simulator's Modbus TCP side")
        code, text, _ = mbpoll(sim_port, BOARD, "0", 4, 1, 1)
        self.assertEqual(code, 0, text)
        self.assertEqual(tcp_sim.get(BOARD, "coil", 4, 2), [1, 1])
        code, text, coils = mbpoll(sim_port, BOARD, "0", 0, count=8)
        self.assertEqual(code, 0, text)
        self.assertEqual(coils, tcp_sim.get(BOARD, "coil", 0, 8))
        self.assertEqual(coils[4:6], [1, 1])


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "share", ShareTest)
