#!/usr/bin/env python3
"""PDU power logging: rosbag records the node's telemetry and the bag reads back."""
import os
import subprocess
import unittest

import rosbag
import rospkg
import rospy
import rostest

from modbus_rtu_driver.msg import PduTelemetry

BAG = "/tmp/modbus_rtu_rostest_bag/telemetry.bag"


class BagTest(unittest.TestCase):
    def test_record_and_read_back(self):
        rospy.init_node("test_bag")
        rospy.wait_for_message("/bus/pdu/telemetry", PduTelemetry, timeout=20)
        os.makedirs(os.path.dirname(BAG), exist_ok=True)
        if os.path.exists(BAG):
            os.remove(BAG)
        subprocess.run(["rosbag", "record", "--duration=3", "-O", BAG, "/bus/pdu/telemetry",
                        "/bus/relays/outputs"], check=True, timeout=30,
                       stdout=subprocess.DEVNULL)
        with rosbag.Bag(BAG) as bag:
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
        png = os.path.join(os.path.dirname(BAG), "telemetry.png")
        if os.path.exists(png):
            os.remove(png)
        script = os.path.join(rospkg.RosPack().get_path("modbus_rtu_driver"), "scripts", "plot_bag.py")
        out = subprocess.run(["/usr/bin/python3", script, BAG, "-o", png, "--node", "/bus"],
                             check=True, timeout=120, stdout=subprocess.PIPE, text=True).stdout
        self.assertIn("%d telemetry samples" % len(telemetry), out)
        with open(png, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertGreater(os.path.getsize(png), 10000)


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "bag", BagTest)
