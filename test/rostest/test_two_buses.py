#!/usr/bin/env python3
"""Several buses on one robot (issue 33 item 2, README "Several buses on one robot"): each bus's
recorder records its own bus node only, even beside a node of the same name in another
namespace, into a bag of its own name; launch/two_bus_example.launch brings up two buses, each
with its own simulator, share port and bag; scripts/plot_bag.py draws both bags as one
figure. Every simulator has its own pty link in a temporary folder; every port is a free one."""
import glob
import os
import shutil
import subprocess
import unittest

import rosbag
import rosgraph
import rospy
import rostest

from modbus_rtu_driver.msg import PduTelemetry, SignalValues

import user_paths as up
from helpers import wait_until
from mbap_client import MbapClient, read_pdu  # test/mbap_client.py: helpers puts test/ on the path

RECORDED_LEAVES = ("telemetry", "limits", "outputs", "inputs", "pwm", "signals", "failsafe")


def bag_topics(path):
    with rosbag.Bag(path) as bag:
        return {t: i.message_count for t, i in bag.get_type_and_topic_info().topics.items()}


def subscriptions(node):
    """The topics `node` subscribes to, as the master knows them."""
    state = rosgraph.Master("/test_two_buses").getSystemState()[1]
    return {topic for topic, nodes in state if node in nodes}


class TwoBusesTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_two_buses")
        cls.dir = up.scratch_dir("modbus_rtu_two_buses_")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def check_own_bag(self, bag, node, others):
        """The bag holds `node`'s topics (outputs and telemetry at least, with messages),
        /diagnostics, and nothing of the other bus nodes."""
        topics = bag_topics(bag)
        for topic, count in topics.items():
            self.assertTrue(topic == "/diagnostics" or topic.startswith(node + "/"),
                            "%s holds %s, not %s's" % (bag, topic, node))
            self.assertTrue(topic == "/diagnostics" or topic.endswith(RECORDED_LEAVES), topic)
            for other in others:
                self.assertFalse(topic.startswith(other + "/"), "%s holds %s" % (bag, topic))
        return topics

    def test_same_named_buses_in_two_namespaces_record_their_own_bags(self):
        """/left/modbus_bus and /right/modbus_bus, both recording with the default bag prefix,
        started together: two bags, each with its own node's topics only."""
        home = os.path.join(self.dir, "home")
        os.makedirs(home)
        sims, links = [], {}
        for side in ("left", "right"):
            links[side] = os.path.join(self.dir, side + "_tty")
            sims.append(up.start_simulator(os.path.join(up.REPO, "config", "simulator.yaml"),
                                           links[side], self.dir, side + "_sim"))
        launch_file = os.path.join(self.dir, "same_names.launch")
        config = os.path.join(up.REPO, "config", "demo.yaml")
        with open(launch_file, "w") as f:
            f.write("<launch>%s</launch>" % "".join("""
  <group ns="%s"><include file="$(find modbus_rtu_driver)/launch/bus.launch">
    <arg name="config" value="%s"/> <arg name="port" value="%s"/>
    <arg name="record" value="true"/> <arg name="required" value="false"/>
  </include></group>""" % (side, config, links[side]) for side in ("left", "right")))
        # The default prefix is under $HOME: a home of its own for this run.
        env = dict(os.environ, HOME=home)
        launch = up.Process(["roslaunch", launch_file], self.dir, "same_names", env=env)
        _, devices = up.bus_devices(config)
        try:
            for side in ("left", "right"):
                node = "/%s/modbus_bus" % side
                for name, device in devices.items():
                    up.check_device_answers(node, name, device, up.REPO, launch)
                # Recording its own telemetry; bounded wait for the recorder's subscriptions.
                wait_until(lambda: node + "/pdu/telemetry" in subscriptions(node + "_record"),
                           30, "the %s recorder on %s/pdu/telemetry" % (side, node))
            for side, other in (("left", "right"), ("right", "left")):
                theirs = [t for t in subscriptions("/%s/modbus_bus_record" % side)
                          if t.startswith("/%s/" % other)]
                self.assertEqual(theirs, [], "the %s recorder records the %s bus" % (side, other))
            # A few telemetry messages of each bus reach the bags (2 Hz).
            for side in ("left", "right"):
                up.wait_for_message("/%s/modbus_bus/pdu/telemetry" % side, PduTelemetry,
                                    lambda m: True, lambda: None)
        finally:
            launch.stop()
            for sim in sims:
                sim.stop()
        for side, other in (("left", "right"), ("right", "left")):
            bags = glob.glob(os.path.join(home, "modbus_rtu_%s_modbus_bus_*.bag" % side))
            self.assertEqual(len(bags), 1, "%s: %s" % (side, sorted(os.listdir(home))))
            topics = self.check_own_bag(bags[0], "/%s/modbus_bus" % side,
                                        ["/%s/modbus_bus" % other])
            self.assertIn("/%s/modbus_bus/relays/outputs" % side, topics)

    def test_two_bus_example_launch_and_one_plot_of_its_bags(self):
        """launch/two_bus_example.launch as the README runs it (links, bags and share ports
        moved to this run's own): every device of both buses answers, each share serves its
        own bus, each bag holds its own bus, plot_bag.py draws both bags in one figure."""
        out = os.path.join(self.dir, "example")
        os.makedirs(out)
        ports = {"io": up.free_port(), "sensor": up.free_port()}
        while ports["sensor"] == ports["io"]:
            ports["sensor"] = up.free_port()
        launch = up.roslaunch(out, "roslaunch", "two_bus_example.launch", "dir:=" + out,
                              "bag_dir:=" + out,
                              "io_share:=127.0.0.1:%d" % ports["io"],
                              "sensor_share:=127.0.0.1:%d" % ports["sensor"])
        buses = {"/io_bus": os.path.join(up.REPO, "config", "demo.yaml"),
                 "/sensor_bus": os.path.join(up.REPO, "config", "generic.yaml")}
        try:
            for node, config in buses.items():
                _, devices = up.bus_devices(config)
                for name, device in devices.items():
                    up.check_device_answers(node, name, device, os.path.dirname(config), launch)
            # io_bus's share reaches its relay board (unit 8: FC01 answered); sensor_bus's share
            # is another bus: no unit 8 there (exception 0B, the device did not answer).
            with MbapClient(ports["io"], 8, timeout=15) as client:
                pdu = client.request(read_pdu(0, 8))
            self.assertEqual(pdu[0], 1, pdu.hex())
            with MbapClient(ports["sensor"], 8, timeout=15) as client:
                pdu = client.request(read_pdu(0, 8))
            self.assertEqual(pdu[:2], b"\x81\x0b", pdu.hex())
            for node in buses:
                wait_until(lambda: any(t.startswith(node + "/")
                                       for t in subscriptions(node + "_record")),
                           30, node + "'s recorder")
            up.wait_for_message("/sensor_bus/climate/signals", SignalValues, lambda m: True,
                                lambda: None)
        finally:
            launch.stop()
        # Stopped as Ctrl-C stops it: both nodes' shutdown safe writes reach their simulators,
        # which are stopped at the same time (issue 48 item 4).
        up.assert_shutdown_safe_writes_confirmed(self, launch.output(), ["relays", "drive"])
        bags = []
        for node, other in (("/io_bus", "/sensor_bus"), ("/sensor_bus", "/io_bus")):
            found = glob.glob(os.path.join(out, "modbus_rtu%s_*.bag" % node.replace("/", "_")))
            self.assertEqual(len(found), 1, sorted(os.listdir(out)))
            self.check_own_bag(found[0], node, [other])
            bags += found
        png = os.path.join(out, "robot.png")
        proc = subprocess.run(["/usr/bin/python3", os.path.join(up.REPO, "scripts", "plot_bag.py")]
                              + bags + ["-o", png], capture_output=True, text=True, timeout=120)
        self.assertEqual(proc.returncode, 0, proc.stdout + proc.stderr)
        self.assertIn("bus node(s) /io_bus, /sensor_bus;", proc.stdout)
        self.assertNotIn(" 0 signal messages", proc.stdout)
        self.assertNotIn(" 0 output messages", proc.stdout)
        with open(png, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "two_buses", TwoBusesTest)
