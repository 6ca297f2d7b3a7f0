#!/usr/bin/env python3
"""A generic device (address 7: the SDM120 template plus writable signals) beside the three
built-in types: reads follow the simulator, writes land in its registers, bad values are refused
with nothing written, and the merged read the device refuses (input registers 2-5 answer
exception 02) is split and reported in /diagnostics. Signals with write_function 16 / 15 go out
as those frames (the node's wire_log shows them) and land; /diagnostics shows each poll group's
achieved rate beside its configured one."""
import struct
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from std_msgs.msg import Bool, Float64
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import SignalValues
from modbus_rtu_driver.srv import SetValue

import helpers

NS = "/bus/meter/"
METER = "7"


def float_words(value):
    """float32 as two registers, most significant first (the SDM120's word order)."""
    hi, lo = struct.unpack(">HH", struct.pack(">f", value))
    return hi, lo


class GenericDeviceTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_generic")
        cls.sim = helpers.sim()
        cls.statuses = {}
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diag)
        cls.signals = helpers.Latest(NS + "signals", SignalValues)
        cls.signals.wait(20, what="the first signals message")

    @classmethod
    def on_diag(cls, msg):
        for s in msg.status:
            cls.statuses[s.name.split(": ", 1)[-1]] = s

    def status(self, device):
        return self.statuses.get("device " + device)

    def status_values(self, device):
        """The device's /diagnostics values by key, or None before its first status."""
        s = self.status(device)
        return None if s is None else {v.key: v.value for v in s.values}

    def value(self, msg, name):
        i = msg.names.index(name)
        return msg.values[i], msg.valid[i]

    def test_reads_follow_the_device(self):
        self.sim.set(METER, "input_register", 0, *float_words(230.5))
        self.sim.set(METER, "input_register", 6, *float_words(1.25))
        self.sim.set(METER, "discrete_input", 0, 1)
        voltage = helpers.Latest(NS + "voltage", Float64)
        voltage.wait(10, lambda m: m.data == 230.5, "230.5 V latched")
        helpers.Latest(NS + "current", Float64).wait(10, lambda m: m.data == 1.25, "1.25 A")
        helpers.Latest(NS + "alarm", Bool).wait(10, lambda m: m.data, "the alarm bit")
        msg = self.signals.wait(10, lambda m: self.value(m, "voltage") == (230.5, True) and
                                self.value(m, "current") == (1.25, True), "D/signals")
        self.assertIn("total_energy", msg.names)
        self.assertTrue(all(msg.valid), list(zip(msg.names, msg.valid)))
        self.assertGreater(msg.header.stamp.to_sec(), 0)

    def test_writes_reach_the_device(self):
        setpoint = helpers.service(NS + "setpoint/set", SetValue)
        # A value between the register's steps (0.1 C): both numbers in the signal's unit
        # (issue 33 item 5: "written as 1" did not say in which unit).
        res = setpoint(21.54)
        self.assertTrue(res.success, res.message)
        self.assertIn("setpoint set to 21.54 C (written as 21.5 C)", res.message)
        res = setpoint(21.5)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(METER, "holding_register", 100), [215])
        res = setpoint(-12.3)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(METER, "holding_register", 100), [0x10000 - 123])  # int16
        counter = helpers.service(NS + "counter/set", SetValue)
        res = counter(65538)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(METER, "holding_register", 102, 2), [2, 1])  # little word order
        relay = helpers.service(NS + "relay/set", SetBool)
        res = relay(True)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(METER, "coil", 0), [1])
        helpers.Latest(NS + "relay", Bool).wait(10, lambda m: m.data, "the relay latched on")
        helpers.Latest(NS + "setpoint", Float64).wait(10, lambda m: abs(m.data + 12.3) < 1e-9,
                                                      "the setpoint latched")

    def sent_frames(self):
        """Requests the node sent, from its wire_log."""
        return [f[3] for f in helpers.wire_log(rospy.get_param("~wire_log")) if f[0] == "tx"]

    def test_write_function_16_and_15_for_one_value(self):
        limit = helpers.service(NS + "limit/set", SetValue)
        res = limit(1234)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(METER, "holding_register", 104), [1234])
        lamp = helpers.service(NS + "lamp/set", SetBool)
        res = lamp(True)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(METER, "coil", 1), [1])
        # FC16 to register 104 (0x68): 1 register, 2 bytes, 1234 = 0x04D2; FC15 to coil 1: 1 coil,
        # 1 byte, bit 0 (the CRC follows).
        fc16 = bytes.fromhex("07 10 00 68 00 01 02 04 D2")
        fc15 = bytes.fromhex("07 0F 00 01 00 01 01 01")
        def both_logged():  # the log is written off the bus thread, a moment after the write
            frames = self.sent_frames()
            bodies = [x[:-2] for x in frames]
            return frames if fc16 in bodies and fc15 in bodies else None
        frames = helpers.wait_until(both_logged, 10, "the FC16 and FC15 frames in the wire log")
        # Never as the single writes (FC06 to register 104, FC05 to coil 1).
        self.assertFalse([x.hex() for x in frames if x[:4] in (bytes.fromhex("07 06 00 68"),
                                                               bytes.fromhex("07 05 00 01"))])

    def test_each_poll_group_shows_its_achieved_rate(self):
        # meter: group 0 at the device's 5 Hz, group 1 the template's energies at 0.2 Hz. Wide
        # bounds (a loaded machine may poll slower): the point is that each group is measured on
        # its own; the sum of both (about 5 Hz) is far outside group 1's bounds.
        def rates_near_configured():
            kv = self.status_values("meter")
            if kv is None:
                return None
            if "poll group 0 achieved [Hz]" not in kv or "poll group 1 achieved [Hz]" not in kv:
                return None
            for g in ("0", "1"):
                configured = float(kv["poll group %s [Hz]" % g])
                achieved = float(kv["poll group %s achieved [Hz]" % g])
                if not 0.3 * configured <= achieved <= 1.5 * configured:
                    return None
            return kv
        kv = helpers.wait_until(rates_near_configured, 40, "each poll group near its own rate")
        self.assertEqual(float(kv["poll group 0 [Hz]"]), 5.0)
        self.assertEqual(float(kv["poll group 1 [Hz]"]), 0.2)
        self.assertNotIn("poll group 2 [Hz]", kv)
        # The scheduler's figure (all groups' polls together) is not shown for a generic device.
        self.assertNotIn("poll rate achieved [Hz]", kv)
        self.assertIn("poll rate achieved [Hz]", {v.key for v in self.status("relays").values})

    def test_bad_values_are_refused_and_nothing_is_written(self):
        self.sim.set(METER, "holding_register", 100, 100)
        self.sim.set(METER, "holding_register", 102, 5, 0)
        before = self.sim.command("stats " + METER)
        setpoint = helpers.service(NS + "setpoint/set", SetValue)
        res = setpoint(50.5)
        self.assertFalse(res.success)
        self.assertIn("setpoint: 50.5 C is outside -20 to 50 C", res.message)
        res = setpoint(float("nan"))
        self.assertFalse(res.success)
        counter = helpers.service(NS + "counter/set", SetValue)
        res = counter(-1)
        self.assertFalse(res.success)
        self.assertIn("outside what uint32 holds", res.message)
        res = counter(4294967296)
        self.assertFalse(res.success)
        self.assertEqual(self.sim.get(METER, "holding_register", 100), [100])
        self.assertEqual(self.sim.get(METER, "holding_register", 102, 2), [5, 0])
        self.assertEqual(self.sim.command("stats " + METER), before)  # no write reached it
        # Read-only signals have no set service.
        with self.assertRaises(rospy.ROSException):
            rospy.wait_for_service(NS + "voltage/set", timeout=1.0)

    def test_refused_merged_read_is_split_and_reported(self):
        def split_reported():
            kv = self.status_values("meter")
            split = kv is not None and kv.get("merged reads split (device refused them)", "0")
            return kv if split and split != "0" else None
        kv = helpers.wait_until(split_reported, 20, "the split in /diagnostics")
        self.assertIn("input_register 0-31", kv["split 0"])
        self.assertIn("refused (exception 02)", kv["split 0"])
        # Both sides of the hole are read since.
        self.sim.set(METER, "input_register", 0, *float_words(199.0))
        self.sim.set(METER, "input_register", 30, *float_words(0.5))
        self.signals.wait(10, lambda m: self.value(m, "voltage") == (199.0, True) and
                          self.value(m, "power_factor") == (0.5, True), "both parts read")

    def test_the_built_in_devices_share_the_bus(self):
        def all_online():
            names = ["relays", "pwm_board", "pdu", "meter"]
            got = [self.status(n) for n in names]
            return all(s is not None and s.level == DiagnosticStatus.OK for s in got)
        helpers.wait_until(all_online, 20, "all four devices online and OK")
        relays = helpers.service("/bus/relays/out0/set", SetBool)
        self.assertTrue(relays(True).success)
        self.assertEqual(self.sim.get("8", "coil", 0), [1])


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "generic", GenericDeviceTest)
