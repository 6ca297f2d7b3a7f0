#!/usr/bin/env python3
"""LC relay board (at 8: beside an LD58A08, its factory 255 would collide) through the bus node: every service and topic
changes the simulated board's coils, and polled states follow changes on the board's side."""
import time
import unittest

import rospy
import rostest
from std_msgs.msg import Bool
from std_srvs.srv import SetBool

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

from modbus_rtu_driver.msg import DigitalStates
from modbus_rtu_driver.srv import Pulse, SetOutputs

import helpers

NS = "/bus/relays/"
BOARD = "8"  # the simulator names devices by address


class LcRelay8Test(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_lc_relay8")
        cls.sim = helpers.sim()
        cls.outputs = helpers.Latest(NS + "outputs", DigitalStates)
        cls.inputs = helpers.Latest(NS + "inputs", DigitalStates)
        cls.outputs.wait(20, what="the first outputs message")

    def coils(self):
        return self.sim.get(BOARD, "coil", 0, 8)

    def test_set_bool_per_channel_writes_the_coil(self):
        set_lamp = helpers.service(NS + "lamp/set", SetBool)
        res = set_lamp(True)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.coils()[2], 1)
        # Latched, but published by the node's publishing thread after the service answered:
        # an earlier latched "off" may still be what a new subscriber gets for a moment.
        helpers.wait_until(lambda: rospy.wait_for_message(NS + "lamp/state", Bool, 5).data, 5,
                           "lamp/state true")
        self.outputs.wait(5, lambda m: m.states[2], "lamp on in outputs")
        self.assertEqual(list(self.outputs.msg.names[:3]), ["pump", "valve", "lamp"])
        res = set_lamp(False)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.coils()[2], 0)

    def test_set_outputs_writes_several_channels(self):
        set_outputs = helpers.service(NS + "set_outputs", SetOutputs)
        res = set_outputs(channels=[0, 3, 7], states=[True, True, True])
        self.assertTrue(res.success, res.message)
        coils = self.coils()
        self.assertEqual([coils[0], coils[3], coils[7]], [1, 1, 1])
        res = set_outputs(channels=[0, 3, 7], states=[False, False, False])
        self.assertTrue(res.success, res.message)
        coils = self.coils()
        self.assertEqual([coils[0], coils[3], coils[7]], [0, 0, 0])

    def test_command_topic_writes_the_coil(self):
        pub = rospy.Publisher(NS + "fan/command", Bool, queue_size=1, latch=True)
        pub.publish(Bool(True))
        helpers.wait_until(lambda: self.coils()[3] == 1, 10, "coil 3 on after fan/command")
        pub.publish(Bool(False))
        helpers.wait_until(lambda: self.coils()[3] == 0, 10, "coil 3 off after fan/command")

    def test_pulse_flash_close_reverts_on_the_board(self):
        pulse = helpers.service(NS + "pulse", Pulse)
        res = pulse(channel=1, state=True, duration=0.6)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.coils()[1], 1, "flash-close turns the relay on at once")
        self.outputs.wait(5, lambda m: m.states[1], "valve on during the flash")
        helpers.wait_until(lambda: self.coils()[1] == 0, 5, "the board to revert the flash")
        self.outputs.wait(5, lambda m: not m.states[1], "the polled state to follow the revert")

    def test_pulse_flash_open_reverts_on(self):
        pulse = helpers.service(NS + "pulse", Pulse)
        res = pulse(channel=5, state=False, duration=0.4)
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.coils()[5], 0)
        helpers.wait_until(lambda: self.coils()[5] == 1, 5, "flash-open to end with the relay on")
        helpers.service(NS + "out5/set", SetBool)(False)

    def test_inputs_follow_the_board(self):
        self.sim.set(BOARD, "discrete_input", 1, 1)
        self.inputs.wait(5, lambda m: m.states[1], "estop active in inputs")
        self.assertEqual(list(self.inputs.msg.names[:2]), ["door", "estop"])
        helpers.wait_until(lambda: rospy.wait_for_message(NS + "estop/state", Bool, 5).data, 5,
                           "estop/state true")
        self.sim.set(BOARD, "discrete_input", 1, 0)
        self.inputs.wait(5, lambda m: not m.states[1], "estop released in inputs")

    def test_diagnostics_per_bus_and_device(self):
        def complete(msg):
            names = [s.name for s in msg.status]
            return any("device relays" in n for n in names) and any("bus " in n for n in names)
        msg = helpers.wait_until(
            lambda: (lambda m: m if complete(m) else None)(
                rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=5)),
            15, "bus and device statuses on /diagnostics")
        by_name = {s.name.split(": ", 1)[-1]: s for s in msg.status}
        relays = next(s for n, s in by_name.items() if "device relays" in n)
        self.assertEqual(relays.level, DiagnosticStatus.OK, relays.message)
        values = {kv.key: kv.value for kv in relays.values}
        self.assertEqual(values["address"], "8")
        self.assertEqual(values["online"], "True")
        bus = next(s for n, s in by_name.items() if n.startswith("bus "))
        bus_values = {kv.key: kv.value for kv in bus.values}
        self.assertGreater(int(bus_values["requests"]), 0)
        for key in ("timeouts", "crc errors", "wrong address", "exceptions", "latency mean [ms]"):
            self.assertIn(key, bus_values)

    def test_bad_values_are_refused_and_nothing_is_written(self):
        before = self.coils()
        pulse = helpers.service(NS + "pulse", Pulse)
        res = pulse(channel=1, state=True, duration=0.0)
        self.assertFalse(res.success)
        self.assertIn("duration", res.message)
        res = pulse(channel=8, state=True, duration=1.0)
        self.assertFalse(res.success)
        self.assertIn("channel", res.message)
        set_outputs = helpers.service(NS + "set_outputs", SetOutputs)
        res = set_outputs(channels=[1, 9], states=[True, True])
        self.assertFalse(res.success)
        self.assertIn("channel", res.message)
        res = set_outputs(channels=[1, 2], states=[True])
        self.assertFalse(res.success)
        self.assertIn("states", res.message)
        time.sleep(0.3)
        self.assertEqual(self.coils(), before)


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "lc_relay8", LcRelay8Test)
