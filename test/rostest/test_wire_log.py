#!/usr/bin/env python3
"""wire_log: the node writes every frame it sends and reads, "tx|rx FIRST LAST HEX cpu=..."
with CLOCK_MONOTONIC seconds; each request is followed by its reply from the same slave, every frame
has a valid CRC, times run forward, and a service write shows as its frame."""
import time
import unittest

import rospy
import rostest
from std_srvs.srv import SetBool

import helpers


def crc16(data):
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


class WireLogTest(unittest.TestCase):
    def test_frames_in_the_log(self):
        rospy.init_node("test_wire_log", anonymous=True)
        path = rospy.get_param("~wire_log")
        set_lamp = helpers.service("/bus/relays/lamp/set", SetBool)
        started = time.monotonic()
        res = set_lamp(True)
        self.assertTrue(res.success, res.message)
        # The write to coil 2 of slave 8 (FC05, ON = FF00) and its echo, after the call began.
        write = bytes([0x08, 0x05, 0x00, 0x02, 0xFF, 0x00])

        def logged():  # the log once it holds the write, the line after it and 10 more
            # (a count reached by waiting, not by luck: under load the write can come among
            # the first frames, a stress-ng run found 10 lines at the first look)
            got = helpers.wire_log(path)
            return got if len(got) > 10 and any(
                f[0] == "tx" and f[3][:6] == write and f[1] >= started for f in got[:-1]) else None
        log = helpers.wait_until(logged, 20, "the lamp's write, its echo and 11 frames in " + path)
        pairs = 0
        for i, (direction, first, last, frame, cpu, waits) in enumerate(log):
            if direction == "tx":
                self.assertEqual(len(waits), 2, "late= and guard=")
                self.assertGreaterEqual(min(waits), 0.0)
            else:
                self.assertIsNone(waits)
            self.assertIn(direction, ("tx", "rx"))
            self.assertLessEqual(first, last)
            self.assertGreaterEqual(len(frame), 4)
            self.assertEqual(crc16(frame[:-2]), frame[-2] | frame[-1] << 8, frame.hex())
            if i > 0:
                self.assertGreaterEqual(first, log[i - 1][2], "times run forward")
                self.assertGreaterEqual(cpu, log[i - 1][4], "the bus thread's CPU time too")
            if direction == "rx":
                request = log[i - 1]
                self.assertEqual(request[0], "tx", "a reply follows its request")
                self.assertEqual(request[3][0], frame[0], "from the slave asked")
                pairs += 1
        self.assertGreater(pairs, 5)
        index = next(i for i, f in enumerate(log[:-1]) if f[0] == "tx" and f[3][:6] == write
                     and f[1] >= started)
        self.assertEqual(log[index + 1][3][:6], write, "the board echoes the write")


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "wire_log", WireLogTest)
