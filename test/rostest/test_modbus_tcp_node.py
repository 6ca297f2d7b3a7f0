#!/usr/bin/env python3
"""The node on tcp:// against pymodbus's Modbus TCP server (an independent implementation): it
connects once the server is up (connect retried with backoff), polls the board's relays and
inputs, writes relays through its services (checked in the server's coils) and says
"Modbus TCP" in /diagnostics."""
import os
import sys
import threading
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
try:
    from pymodbus.server import StartTcpServer
except ImportError:  # pymodbus 2 (Debian 11's 2.1, Ubuntu 20.04's): the same server, elsewhere
    from pymodbus.server.sync import StartTcpServer
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import DigitalStates

import helpers

NS = "/bus/relays/"
COILS, INPUTS = 1, 2  # pymodbus function codes naming the tables


def block():
    return ModbusSequentialDataBlock(0, [0] * 64)


class ModbusTcpNodeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_modbus_tcp_node")
        cls.port = rospy.get_param("~server_port")  # chosen free by run_rostest.py
        tables = dict(co=block(), di=block(), hr=block(), ir=block())
        try:
            cls.store = ModbusSlaveContext(zero_mode=True, **tables)
        except TypeError:
            # pymodbus 3.7+ (Debian 13's 3.8) has no zero_mode: its context always shifts
            # addresses by one, for the server's requests and this test's get/setValues alike.
            cls.store = ModbusSlaveContext(**tables)
        context = ModbusServerContext(slaves={1: cls.store}, single=False)
        threading.Thread(target=StartTcpServer, daemon=True,
                         kwargs=dict(context=context, address=("127.0.0.1", cls.port))).start()
        cls.bus = None
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diag)
        cls.outputs = helpers.Latest(NS + "outputs", DigitalStates)
        cls.inputs = helpers.Latest(NS + "inputs", DigitalStates)

    @classmethod
    def on_diag(cls, msg):
        for s in msg.status:
            if "bus " in s.name:
                cls.bus = s

    def value(self, key):
        for kv in self.bus.values if self.bus else []:
            if kv.key == key:
                return kv.value
        return None

    def coil(self, channel):
        return bool(self.store.getValues(COILS, channel, 1)[0])

    def test_polls_writes_and_reports_modbus_tcp(self):
        self.outputs.wait(30, what="the first outputs message (the node connected)")
        self.store.setValues(COILS, 6, [1])  # changed on the server's side
        self.outputs.wait(10, lambda m: m.states[6], "coil 6 on in the polled outputs")
        before = self.inputs.wait(10, what="the first inputs message").states[3]
        self.store.setValues(INPUTS, 3, [0 if self.store.getValues(INPUTS, 3, 1)[0] else 1])
        self.inputs.wait(10, lambda m: m.states[3] != before, "input 3 to follow the server")

        set_lamp = helpers.service(NS + "lamp/set", SetBool)
        for state in (True, False):
            res = set_lamp(state)
            self.assertTrue(res.success, res.message)
            self.assertEqual(self.coil(2), state)
        helpers.wait_until(lambda: self.value("transport") == "Modbus TCP", 10,
                           "/diagnostics naming the transport")
        self.assertEqual(self.value("port"), "tcp://127.0.0.1:%d" % self.port)
        self.assertEqual(self.value("failed"), "0")


if __name__ == "__main__":
    code = 0
    try:
        rostest.rosrun("modbus_rtu_driver", "modbus_tcp_node", ModbusTcpNodeTest)
    except SystemExit as e:
        code = e.code if isinstance(e.code, int) else 1
    except AttributeError as e:
        # Debian 11's rospy (1.15.9) calls Thread.isAlive, gone in Python 3.9, at shutdown when
        # threads that are not daemons are left: after the results were written.
        if "isAlive" not in str(e):
            raise
    # pymodbus 2.1 (Debian 11, Ubuntu 20.04) serves each connection on a thread that is not a
    # daemon, and the node keeps its connection open: without this the process never ends and
    # rostest reports a time-out although the result file says every case passed.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
