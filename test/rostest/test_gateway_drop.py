#!/usr/bin/env python3
"""The node on rtu+tcp:// when its gateway reboots: the connection drops, the node reconnects
with backoff, /diagnostics shows the transport and counts the reconnect, and writes work again
(checked in the simulator's coils). A write during the outage is never reported done unless
it was."""
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from std_srvs.srv import SetBool

import helpers

NS = "/bus/relays/"
BOARD = "8"


class GatewayDropTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_gateway_drop")
        cls.sim = helpers.sim()
        cls.bus = None
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diag)

    @classmethod
    def on_diag(cls, msg):
        for s in msg.status:
            if "bus " in s.name:
                cls.bus = s

    def value(self, key):
        status = self.bus
        for kv in status.values if status else []:
            if kv.key == key:
                return kv.value
        return None

    def gateway(self):
        words = self.sim.command("gateway")  # port P connections N accepted N dropped N
        return dict(zip(words[0::2], map(int, words[1::2])))

    def test_reconnects_after_the_gateway_reboots(self):
        set_lamp = helpers.service(NS + "lamp/set", SetBool)
        helpers.wait_until(lambda: self.value("transport") == "RTU over TCP", 20,
                           "the bus status naming the transport")
        self.assertEqual(self.value("port"), rospy.get_param("/bus/port"))
        self.assertTrue(self.value("port").startswith("rtu+tcp://127.0.0.1:"), self.value("port"))
        res = set_lamp(True)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.sim.get(BOARD, "coil", 0, 8)[2], 1)
        before = int(self.value("reconnects"))
        accepted = self.gateway()["accepted"]

        self.sim.command("gateway_drop 1500")  # closes the connection, down for 1.5 s
        res = set_lamp(False)  # during the outage: either refused or really done
        if res.success:
            self.assertEqual(self.sim.get(BOARD, "coil", 0, 8)[2], 0, res.message)
        else:
            rospy.loginfo("write during the outage refused: %s", res.message)

        helpers.wait_until(lambda: self.gateway()["accepted"] > accepted, 30,
                           "the node to connect to the gateway again")
        helpers.wait_until(lambda: int(self.value("reconnects")) > before, 15,
                           "/diagnostics to count the reconnect")
        helpers.wait_until(lambda: self.bus.level != DiagnosticStatus.ERROR and
                           "link up" in self.bus.message, 15, "the link up again")
        self.assertGreaterEqual(self.gateway()["dropped"], 1)
        for state in (True, False):  # a write after the reconnect goes through and is done
            res = set_lamp(state)
            self.assertTrue(res.success, res.message)
            self.assertEqual(self.sim.get(BOARD, "coil", 0, 8)[2], int(state))


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "gateway_drop", GatewayDropTest)
