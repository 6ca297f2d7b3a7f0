#!/usr/bin/env python3
"""The raw write services: refused with a clear message unless allow_raw_writes is set (~allowed
says which this launch has); bad fields named; nothing reaches the bus when refused; a confirmed
write lands in the simulated device's registers."""
import unittest

import rospy
import rostest

from modbus_rtu_driver.srv import WriteCoils, WriteRegisters

import helpers

NS = "/bus/"


class RawWritesTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_raw_writes", anonymous=True)
        cls.sim = helpers.sim()
        cls.allowed = rospy.get_param("~allowed")
        cls.registers = helpers.service(NS + "write_registers", WriteRegisters)
        cls.coils = helpers.service(NS + "write_coils", WriteCoils)

    def refused(self, call, *fragments):
        """call() must fail naming `fragments`, and the PDU's registers must stay."""
        before_pdu = self.sim.get("2", "holding_register", 0, 3)
        res = call()
        self.assertFalse(res.success, res.message)
        for f in fragments:
            self.assertIn(f, res.message)
        # Polls go on, so frames keep coming; the registers a write would change must not.
        self.assertEqual(self.sim.get("2", "holding_register", 0, 3), before_pdu)

    def test_refused_or_written(self):
        if not self.allowed:
            self.refused(lambda: self.registers(slave=2, address=0, values=[250, 200, 12]),
                         "raw writes are off", "allow_raw_writes")
            self.refused(lambda: self.coils(slave=2, address=0, values=[True]), "raw writes are off")
            return
        res = self.registers(slave=1, address=0x0010, values=[30, 10, 0])
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get("1", "holding_register", 0x10, 3), [30, 10, 0])
        res = self.coils(slave=1, address=5, values=[True, False, True])
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get("1", "coil", 5, 3), [1, 0, 1])
        res = self.coils(slave=1, address=5, values=[False, False, False])
        self.assertTrue(res.success, res.message)
        # The device refuses: its exception is the answer.
        res = self.registers(slave=2, address=0, values=[100, 200, 12])
        self.assertFalse(res.success)
        self.assertIn("illegal data value", res.message)
        # Nobody at that address: no reply, not success.
        res = self.registers(slave=77, address=0, values=[1])
        self.assertFalse(res.success)
        self.assertIn("no reply", res.message)

    def test_bad_fields_are_named(self):
        if not self.allowed:
            return  # refused before the fields are looked at (checked above)
        self.refused(lambda: self.registers(slave=0, address=0, values=[1]), "slave: 0", "1-255")
        self.refused(lambda: self.registers(slave=2, address=0, values=[]), "values: 0", "1-123")
        self.refused(lambda: self.registers(slave=2, address=0, values=[1] * 124),
                     "values: 124", "1-123")
        self.refused(lambda: self.registers(slave=2, address=65535, values=[1, 2]),
                     "address: 65535", "65535")
        self.refused(lambda: self.coils(slave=2, address=0, values=[True] * 1969),
                     "values: 1969", "1-1968")


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "raw_writes", RawWritesTest)
