#!/usr/bin/env python3
"""A stop through roslaunch with one board silent (issue 24): roslaunch sends SIGINT, SIGTERM
15 s later and SIGKILL 2 s after that. The node must write the answering board's safe state
and end on its own before the escalation; the simulator's coils are checked after exit.
And bus.launch started again after its required node was killed during a flash (issue 48 item
5): the next node resumes the flash, so its end is no restart and nothing is written back."""
import os
import signal
import subprocess
import tempfile
import time
import unittest

import rospkg
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from std_srvs.srv import SetBool

import helpers
from modbus_rtu_driver.msg import FailsafeEvent
from modbus_rtu_driver.srv import Pulse

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

    def test_a_launch_started_again_after_its_node_was_killed_resumes_the_flash(self):
        # docs/failsafe.md, "What the node cannot do": the next node of that name under the
        # same roscore resumes the killed node's running flashes, also when the supervisor
        # starts the whole launch again (bus.launch's clear_params="true").
        rospy.init_node("test_shutdown_roslaunch")
        sim = helpers.sim()
        node = "relaunchbus"
        pkg = rospkg.RosPack().get_path("modbus_rtu_driver")
        args = ["roslaunch", "--wait", "modbus_rtu_driver", "bus.launch", "name:=" + node,
                "config:=" + os.path.join(pkg, "test", "rostest", "relaunch_bus.yaml"),
                "port:=" + rospy.get_param("~port")]
        out5, flash = 5, 10.0
        sim.set(LAMPS, "coil", out5, 0)
        events = []
        sub = rospy.Subscriber("/%s/failsafe" % node, FailsafeEvent, events.append)
        log = tempfile.TemporaryFile(mode="w+")
        first = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT)
        second = None
        try:
            pulse = helpers.service("/%s/lamps/pulse" % node, Pulse, timeout=60)
            res = pulse(out5, True, flash)  # flash-close: on 10 s, then off
            self.assertTrue(res.success, res.message)
            t0 = time.time()
            self.assertEqual(sim.get(LAMPS, "coil", out5, 1), [1])
            pid = helpers.wait_until(lambda: _pid_of("/" + node), 10, "the node's pid")
            os.kill(pid, signal.SIGKILL)  # no code of the node runs; required: the launch ends
            self.assertIsNotNone(_wait(first, 30), "roslaunch did not end with its required node")
            second = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT)
            helpers.service("/%s/lamps/out0/set" % node, SetBool, timeout=60)
            self.assertLess(time.time(), t0 + flash, "the launch came up after the flash's end")
            # Through the flash's end (its slack: 0.5 s + 2 %) and polls after it.
            end = t0 + flash + 0.7 + 2.0
            while time.time() < end:
                if time.time() > t0 + flash + 0.7:
                    self.assertEqual(sim.get(LAMPS, "coil", out5, 1), [0],
                                     "out5 written on again after the flash's end")
                time.sleep(0.05)
            restarts = [e for e in events if e.trigger == "restart"]
            self.assertFalse(restarts, "the flash's end was taken for a restart: %r" % restarts)
        finally:
            sub.unregister()
            for launch in (first, second):
                if launch is not None and launch.poll() is None:
                    launch.send_signal(signal.SIGINT)
                    if _wait(launch, 30) is None:
                        launch.kill()
                        launch.wait()
            log.seek(0)
            print(log.read())


def _pid_of(node):
    """The pid of a running node, from its XML-RPC server (as rosnode does)."""
    import rosgraph
    import xmlrpc.client
    try:
        uri = rosgraph.Master("/test_shutdown_roslaunch").lookupNode(node)
        code, _, pid = xmlrpc.client.ServerProxy(uri).getPid("/test")
        return pid if code == 1 else None
    except (OSError, rosgraph.MasterError):
        return None


def _wait(process, timeout):
    try:
        return process.wait(timeout)
    except subprocess.TimeoutExpired:
        return None


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "shutdown_roslaunch", ShutdownThroughRoslaunch)
