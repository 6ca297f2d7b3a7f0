#!/usr/bin/env python3
"""PDU power logging: rosbag records the node's telemetry and the bag reads back."""
import os
import shutil
import subprocess
import tempfile
import time
import unittest

import rosbag
import rospkg
import rospy
import rostest

from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import DigitalStates, PduTelemetry

class BagTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_bag")

    def test_record_and_read_back(self):
        rospy.wait_for_message("/bus/pdu/telemetry", PduTelemetry, timeout=20)
        # A directory of this run's own: another run beside it cannot take the bag or the PNG.
        work = tempfile.mkdtemp(prefix="modbus_rtu_rostest_bag_")
        self.addCleanup(shutil.rmtree, work, True)
        bag_path = os.path.join(work, "telemetry.bag")
        subprocess.run(["rosbag", "record", "--duration=3", "-O", bag_path, "/bus/pdu/telemetry",
                        "/bus/relays/outputs"], check=True, timeout=30,
                       stdout=subprocess.DEVNULL)
        with rosbag.Bag(bag_path) as bag:
            telemetry = [m for _, m, _ in bag.read_messages(topics=["/bus/pdu/telemetry"])]
            outputs = [m for _, m, _ in bag.read_messages(topics=["/bus/relays/outputs"])]
        # 5 Hz for 3 s; allow for a slow start of the recorder.
        self.assertGreaterEqual(len(telemetry), 5)
        self.assertGreaterEqual(len(outputs), 1)
        stamps = [m.header.stamp.to_sec() for m in telemetry]
        self.assertEqual(stamps, sorted(stamps))
        for m in telemetry:
            self.assertGreater(m.voltage, 150.0)
            self.assertGreater(m.power, -1.0)
        # The plotting script turns the bag into a PNG.
        png = os.path.join(work, "telemetry.png")
        script = os.path.join(rospkg.RosPack().get_path("modbus_rtu_driver"), "scripts", "plot_bag.py")
        out = subprocess.run(["/usr/bin/python3", script, bag_path, "-o", png, "--node", "/bus"],
                             check=True, timeout=120, stdout=subprocess.PIPE, text=True).stdout
        self.assertIn("%d telemetry samples" % len(telemetry), out)
        with open(png, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertGreater(os.path.getsize(png), 10000)

    def test_state_topics_on_change_with_keep_alive(self):
        """publish_on_change: outputs only when a state changes, and every keep_alive (1 s)."""
        counts = {"/bus/relays/outputs": 0, "/bus_onchange/relays/outputs": 0}
        latest = {}

        def counter(topic):
            def cb(msg):
                counts[topic] += 1
                latest[topic] = msg
            return cb
        subs = [rospy.Subscriber(t, DigitalStates, counter(t)) for t in counts]
        deadline = time.time() + 20
        while time.time() < deadline and any(t not in latest for t in counts):
            time.sleep(0.05)
        self.assertEqual(sorted(latest), sorted(counts), "both nodes publish outputs")
        for t in counts:
            counts[t] = 0
        time.sleep(3.0)  # nothing changes meanwhile
        every_poll, on_change = counts["/bus/relays/outputs"], counts["/bus_onchange/relays/outputs"]
        rospy.loginfo("outputs in 3 s: %d every poll (10 Hz), %d on change", every_poll, on_change)
        self.assertGreaterEqual(every_poll, 15)
        self.assertGreaterEqual(on_change, 2, "keep-alive messages")
        self.assertLessEqual(on_change, 5)
        # A change is published at once, not at the next keep-alive only.
        rospy.wait_for_service("/bus_onchange/relays/out6/set", 10)
        res = rospy.ServiceProxy("/bus_onchange/relays/out6/set", SetBool)(True)
        self.assertTrue(res.success, res.message)
        deadline = time.time() + 5
        while time.time() < deadline and not latest["/bus_onchange/relays/outputs"].states[6]:
            time.sleep(0.02)
        self.assertTrue(latest["/bus_onchange/relays/outputs"].states[6])
        for s in subs:
            s.unregister()


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "bag", BagTest)
