#!/usr/bin/env python3
"""A robot's bag: bus.launch with record:=true under a robot's namespace (three output boards
and a generic sensor), a fail-safe action during the recording; the bag holds ~failsafe and the
signals, and scripts/plot_bag.py draws it without being told the node. During the recording the
PDU is unplugged for a while and the node is killed and respawned: the plot breaks the PDU's
lines there, marks the node's stop and restart, and hatches the PWM burst (issue 33 item 3).
MODBUS_RTU_KEEP_PLOTS=DIR keeps the PNG and the bag (docs/robot_telemetry.png comes from it)."""
import glob
import importlib.util
import os
import shutil
import subprocess
import unittest

import rosbag
import rosgraph
import rospy
import rostest
import yaml

from std_msgs.msg import Bool
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import FailsafeEvent, PduTelemetry
from modbus_rtu_driver.srv import SetPwm

import user_paths as up
from helpers import wait_until
from sim_control import SimControl


class RobotBagTest(unittest.TestCase):
    """record:=true on a bus under a robot's namespace with three output boards and a generic
    sensor: the bag holds ~failsafe and the signals, and scripts/plot_bag.py draws it without
    being told the node."""

    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_robot_bag")
        cls.dir = up.scratch_dir("modbus_rtu_robot_bag_")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_record_and_plot_a_namespaced_bus_with_a_generic_device(self):
        templates = os.path.join(up.REPO, "config", "templates")
        devices = {
            "relays": {"type": "lc_relay8", "address": 8, "poll_rate": 5.0,
                       "outputs": ["pump", "valve", "lamp", "fan", "heater", "door_lock",
                                   "siren", "beacon"],
                       "safe_state": {"pump": "off"}, "command_timeout": {"pump": 1.0}},
            "pwm_board": {"type": "ld58a08", "address": 4, "poll_rate": 5.0},
            "pdu": {"type": "yespeed_pdu", "address": 2, "poll_rate": 2.0,
                    "outputs": ["socket%d" % i for i in range(1, 9)]},
            "climate": {"type": "generic", "address": 1, "poll_rate": 2.0,
                        "template": os.path.join(templates, "xy_md02.yaml")},
        }
        config = os.path.join(self.dir, "robot_bus.yaml")
        with open(config, "w") as f:
            yaml.safe_dump({"port": "/dev/null", "baud": 9600, "devices": devices}, f)
        link = os.path.join(self.dir, "tty")
        sim_process = up.start_simulator(up.simulator_config_for(config, self.dir), link,
                                         self.dir)
        sim = SimControl(link + ".ctl")
        sim.set(1, "input_register", 1, 215, 480)  # 21.5 C, 48.0 %RH
        launch_file = os.path.join(self.dir, "robot.launch")
        with open(launch_file, "w") as f:
            f.write("""<launch><group ns="robot">
  <include file="$(find modbus_rtu_driver)/launch/bus.launch">
    <arg name="name" value="io_bus"/> <arg name="config" value="%s"/> <arg name="port" value="%s"/>
    <arg name="record" value="true"/> <arg name="bag" value="%s/robot"/>
    <arg name="required" value="false"/>
    <arg name="respawn" value="true"/> <arg name="respawn_delay" value="5.0"/>
  </include></group></launch>""" % (config, link, self.dir))
        launch = up.Process(["roslaunch", launch_file], self.dir, "roslaunch")
        ns = "/robot/io_bus"
        events = []
        try:
            for name, device in devices.items():
                up.check_device_answers(ns, name, device, os.path.dirname(config), launch)
            master = rosgraph.Master("/test_robot_bag")

            def recording(topic):
                subscribers = dict(master.getSystemState()[1]).get(topic, [])
                return "/robot/io_bus_record" in subscribers
            for topic in ("outputs", "failsafe"):
                full = ns + ("/relays/outputs" if topic == "outputs" else "/failsafe")
                wait_until(lambda: recording(full), 30, "rosbag recording " + full)
            wait_until(lambda: recording(ns + "/climate/signals"), 30, "rosbag recording signals")
            sub = rospy.Subscriber(ns + "/failsafe", FailsafeEvent, events.append)
            # Some life on the robot: relays, sockets, a PWM burst, the room warming.
            for service in ("relays/lamp/set", "pdu/socket2/set", "relays/siren/set"):
                self.assertTrue(up.call("%s/%s" % (ns, service), SetBool, lambda: None,
                                        True).success)
            res = up.call(ns + "/pwm_board/set_pwm", SetPwm, lambda: None, 0, 1.0, 0.5, 6, 0,
                          0, 0.0)
            self.assertTrue(res.success, res.message)
            sim.set(1, "input_register", 1, 230)
            # The pump on by its command topic, then silence: the dead man puts it off.
            pump = rospy.Publisher(ns + "/relays/pump/command", Bool, queue_size=1)
            wait_until(lambda: pump.get_num_connections() > 0, 10, "the pump's command topic")
            pump.publish(Bool(True))
            wait_until(lambda: any(e.trigger == "command_timeout" for e in events), 20,
                       "the command_timeout fail-safe event")
            self.assertTrue(up.call(ns + "/relays/siren/set", SetBool, lambda: None,
                                    False).success)
            sub.unregister()
            # The PDU unplugged for 4 s (8 of its polls: no telemetry), then back.
            telemetry = []
            tsub = rospy.Subscriber(ns + "/pdu/telemetry", PduTelemetry,
                                    lambda m: telemetry.append(m.header.stamp.to_sec()))
            wait_until(lambda: telemetry, 10, "PDU telemetry")
            sim.silence(2)
            unplugged = rospy.get_time()
            wait_until(lambda: rospy.get_time() > unplugged + 4.0, 10, "4 s")
            sim.silence(2, False)
            back = rospy.get_time()
            wait_until(lambda: telemetry[-1] > back, 20, "PDU telemetry after the outage")
            # The node killed: respawned 5 s later (bus.launch respawn:=true), silent for longer than
            # 3 of its /diagnostics periods: plot_bag.py marks the stop too.
            killed = rospy.get_time()
            subprocess.run(["rosnode", "kill", ns], check=True, timeout=30,
                           stdout=subprocess.DEVNULL)
            wait_until(lambda: telemetry[-1] > killed + 5.0, 60, "the respawned node's telemetry")
            again = telemetry[-1]
            wait_until(lambda: telemetry[-1] > again + 3.0, 20, "3 s of the respawned node")
            tsub.unregister()
        finally:
            launch.stop()
            sim_process.stop()
        bags = glob.glob(os.path.join(self.dir, "robot_*.bag"))
        self.assertEqual(len(bags), 1, os.listdir(self.dir))
        with rosbag.Bag(bags[0]) as bag:
            topics = set(bag.get_type_and_topic_info().topics)
        for topic in ("/robot/io_bus/failsafe", "/robot/io_bus/climate/signals",
                      "/robot/io_bus/pdu/telemetry", "/robot/io_bus/relays/outputs"):
            self.assertIn(topic, topics)
        png = os.path.join(self.dir, "robot.png")
        out = subprocess.run(["/usr/bin/python3", os.path.join(up.REPO, "scripts", "plot_bag.py"),
                              bags[0], "-o", png], capture_output=True, text=True, timeout=120)
        self.assertEqual(out.returncode, 0, out.stdout + out.stderr)
        self.assertIn("bus node(s) /robot/io_bus;", out.stdout)
        self.assertNotIn(" 0 signal messages", out.stdout)
        self.assertNotIn(" 0 fail-safe events", out.stdout)
        with open(png, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        keep = os.environ.get("MODBUS_RTU_KEEP_PLOTS")  # for the docs' picture
        if keep:
            shutil.copy(png, os.path.join(keep, "robot_telemetry.png"))
            shutil.copy(bags[0], os.path.join(keep, "robot.bag"))
            with open(os.path.join(keep, "robot_times.txt"), "w") as f:
                f.write("unplugged %f back %f killed %f\n" % (unplugged, back, killed))
        self.check_drawing(bags[0], unplugged, back, killed)

    def check_drawing(self, bag, unplugged, back, killed):
        """What plot_bag.py draws from the bag: the PDU's outage breaks its lines and is
        shaded, the node's stop and restart are marked, the PWM burst is hatched, and no
        fail-safe label overlaps another."""
        spec = importlib.util.spec_from_file_location(
            "plot_bag", os.path.join(up.REPO, "scripts", "plot_bag.py"))
        plot_bag = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(plot_bag)
        drawn = plot_bag.plot(plot_bag.load([bag]), os.path.join(self.dir, "check.png"), "bag")
        t0 = drawn.t0
        panel = {ax.get_ylabel(): ax for ax in drawn.axes}

        def artists(ax, gid):
            return [a for a in ax.get_children() if a.get_gid() == gid]

        def spans(ax, gid):
            # An axvspan is a Rectangle since matplotlib 3.9 (Debian 13), a Polygon before.
            return [(a.get_x() + t0, a.get_x() + a.get_width() + t0) if hasattr(a, "get_width")
                    else (min(x for x, _ in a.get_xy()) + t0, max(x for x, _ in a.get_xy()) + t0)
                    for a in artists(ax, gid)]
        power = panel["power [W]"]
        outages = spans(power, "outage")
        self.assertTrue(any(a <= unplugged + 1.0 and b >= back - 0.5 for a, b in outages),
                        "no outage shaded over %.1f-%.1f: %s" % (unplugged - t0, back - t0,
                                                                  [(a - t0, b - t0)
                                                                   for a, b in outages]))
        for line in artists(power, "series"):
            xs = [x + t0 for x in line.get_xdata()]
            for a, b in zip(xs, xs[1:]):
                self.assertFalse(a <= unplugged + 1.0 and b >= back - 0.5,
                                 "a line runs across the outage: %.1f-%.1f" % (a - t0, b - t0))
        stopped = [line.get_xdata()[0] + t0 for line in artists(power, "node-stopped")]
        restarted = [line.get_xdata()[0] + t0 for line in artists(power, "node-restarted")]
        # The mark is at the node's last message: the stop's own (its safe writes' events, its
        # last polls) may come up to shutdown_timeout after the kill (docs/ros_api.md; 3.0 s by
        # default, this bus's), and the kill itself goes through rosnode. On a loaded machine
        # the mark came 2.05 s after the kill command (a clean clone's test run beside two fresh
        # checks, 2026-12-07).
        stop_may_take = 3.0 + 2.0
        self.assertTrue(any(killed - 2.0 <= t <= killed + stop_may_take for t in stopped),
                        "stop not marked within %.1f-%.1f: %s" % (
                            killed - 2.0 - t0, killed + stop_may_take - t0,
                            [t - t0 for t in stopped]))
        self.assertTrue(any(killed + 5.0 <= t <= killed + 30.0 for t in restarted),
                        "restart not marked: %s" % [t - t0 for t in restarted])
        pwm = artists(panel["pwm_board"], "pwm:0")
        self.assertEqual(len(pwm), 1)
        xs = [x for path in pwm[0].get_paths() for x, _ in path.vertices]
        self.assertGreater(max(xs) - min(xs), 3.0)  # 6 pulses of 1 s, seen by 5 Hz polls
        renderer = drawn.fig.canvas.get_renderer()
        boxes = [a.get_window_extent(renderer) for a in drawn.labels]
        self.assertTrue(boxes)
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                self.assertFalse(boxes[i].overlaps(boxes[j]))


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "robot_bag", RobotBagTest)
