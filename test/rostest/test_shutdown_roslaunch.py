#!/usr/bin/env python3
"""A stop through roslaunch with one board silent (issue 24): roslaunch sends SIGINT, SIGTERM
15 s later and SIGKILL 2 s after that. The node must write the answering board's safe state
and end on its own before the escalation; the simulator's coils are checked after exit."""
import os
import signal
import subprocess
import tempfile
import unittest

import rospkg
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from std_srvs.srv import SetBool

import helpers

NODE = "stopbus"
LAMPS, PWM = "8", "1"


def consecutive_failures(msg, device):
    for status in msg.status:  # "stopbus: device lamps"
        if status.name.endswith("device " + device):
            for kv in status.values:
                if kv.key == "consecutive failures":
                    return int(kv.value)
    return None


class ShutdownThroughRoslaunch(unittest.TestCase):
    def test_the_answering_board_is_safe_and_the_node_ends_before_sigterm(self):
        rospy.init_node("test_shutdown_roslaunch")
        sim = helpers.sim()
        pkg = rospkg.RosPack().get_path("modbus_rtu_driver")
        config = os.path.join(pkg, "test", "rostest", "shutdown_bus.yaml")
        log = tempfile.TemporaryFile(mode="w+")
        launch = subprocess.Popen(
            ["roslaunch", "--wait", "modbus_rtu_driver", "bus.launch", "name:=" + NODE,
             "config:=" + config, "port:=" + rospy.get_param("~port")],
            stdout=log, stderr=subprocess.STDOUT)
        try:
            diagnostics = helpers.Latest("/diagnostics", DiagnosticArray)
            helpers.service("/%s/lamps/out0/set" % NODE, SetBool, timeout=60)(True)
            helpers.service("/%s/pwm_board/out0/set" % NODE, SetBool, timeout=60)(True)
            self.assertEqual(sim.get(LAMPS, "coil", 0, 1), [1])
            self.assertEqual(sim.get(PWM, "coil", 0, 1), [1])
            sim.silence(LAMPS, True)
            # The node has seen the board fail (a poll of it timed out after its retries).
            diagnostics.wait(60, lambda m: (consecutive_failures(m, "lamps") or 0) >= 1,
                             "lamps failing in /diagnostics")
            # The node's INFO lines reach roslaunch's output file while it runs, not only at
            # its exit (stdout is line-buffered; issue 33 item 4).
            log.flush()
            with open("/proc/self/fd/%d" % log.fileno()) as running:
                self.assertRegex(running.read(), r"bus .* at \d+ baud, .* parity: \d+ device")
            launch.send_signal(signal.SIGINT)
            code = launch.wait(60)
        finally:
            if launch.poll() is None:
                launch.kill()
                launch.wait()
            sim.silence(LAMPS, False)
        log.seek(0)
        output = log.read()
        print(output)
        self.assertEqual(code, 0)
        self.assertNotIn("escalating to SIGTERM", output, "roslaunch had to escalate")
        self.assertNotIn("escalating to SIGKILL", output, "roslaunch had to kill the node")
        self.assertEqual(sim.get(PWM, "coil", 0, 1), [0], "the answering board's safe state")
        self.assertEqual(sim.get(LAMPS, "coil", 0, 1), [1], "the silent board kept its state")
        self.assertIn("lamps", output)
        self.assertIn("not confirmed", output.lower())


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "shutdown_roslaunch", ShutdownThroughRoslaunch)
