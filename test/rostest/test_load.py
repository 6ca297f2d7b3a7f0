#!/usr/bin/env python3
"""Load on the real node: 8 clients x 500 SetBool calls at once (every call returns with the
truth, the board ends as the last calls asked), and a command topic flooded (bounded memory,
newest command wins, services still answer)."""
import subprocess
import threading
import time
import unittest

import rospy
import rostest
from std_msgs.msg import Bool
from std_srvs.srv import SetBool

import helpers

NS = "/bus/relays/"
CLIENTS, CALLS = 8, 500
NAMES = ["pump", "valve", "lamp", "fan", "out4", "out5", "out6", "out7"]  # bus_three.yaml


def node_rss_kib():
    """Resident memory of the bus node, from /proc (it runs on this machine)."""
    pid = int(subprocess.check_output(["pgrep", "-f", "modbus_rtu_bus .*__name:=bus"]).split()[0])
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return -1


class LoadTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_load")
        cls.sim = helpers.sim()
        helpers.service(NS + "pump/set", SetBool)

    def test_many_callers(self):
        results = [[] for _ in range(CLIENTS)]
        errors = []

        def client(i):
            try:
                call = rospy.ServiceProxy(NS + NAMES[i] + "/set", SetBool, persistent=True)
                for n in range(CALLS):
                    res = call(n % 2 == 0 if i % 2 else n % 2 == 1)
                    results[i].append(res.success)
                call.close()
            except Exception as e:  # a lost call would end here
                errors.append("client %d: %r" % (i, e))

        frames_before = self.sim.frames()[0]
        t0 = time.time()
        threads = [threading.Thread(target=client, args=(i,)) for i in range(CLIENTS)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(240)
        took = time.time() - t0
        self.assertEqual(errors, [])
        answered = sum(len(r) for r in results)
        succeeded = sum(sum(r) for r in results)
        frames = self.sim.frames()[0] - frames_before
        print("load: %d calls answered, %d succeeded, in %.1f s; %d frames on the line (polls "
              "included): queued writes merged" % (answered, succeeded, took, frames))
        self.assertLess(frames, CLIENTS * CALLS, "queued writes to one board share frames")
        self.assertEqual(answered, CLIENTS * CALLS, "every call returns")
        self.assertEqual(succeeded, CLIENTS * CALLS, "no write failed on a healthy bus")
        # Each board output ends as its client's last call asked.
        final = self.sim.get("8", "coil", 0, 8)
        expected = [int((CALLS - 1) % 2 == 0 if i % 2 else (CALLS - 1) % 2 == 1) for i in range(CLIENTS)]
        self.assertEqual(final, expected)

    def test_command_flood(self):
        # queue_size=None: publish() returns once the message is in the socket to the node, so
        # after the last one nothing older is still waiting in this process.
        pub = rospy.Publisher(NS + "out6/command", Bool, queue_size=None)
        helpers.wait_until(lambda: pub.get_num_connections() > 0, 10, "the node to subscribe")
        rss_before = node_rss_kib()
        set_out5 = helpers.service(NS + "out5/set", SetBool)
        answers = []
        for n in range(5000):
            pub.publish(Bool(n % 2 == 1))
            if n % 1000 == 500:
                t0 = time.time()
                answers.append((set_out5(n % 2 == 0).success, time.time() - t0))
        pub.publish(Bool(True))  # the newest command
        helpers.wait_until(lambda: self.sim.get("8", "coil", 6) == [1], 10, "the newest command")
        # An older "on" may have set it: let the line carry 50 more frames (older commands still
        # in the node would be written by then; the node merges them into one write) and look again.
        after = self.sim.frames()[0] + 50
        helpers.wait_until(lambda: self.sim.frames()[0] >= after, 30, "50 more frames on the line")
        self.assertEqual(self.sim.get("8", "coil", 6), [1], "newest command wins")
        self.assertTrue(all(ok for ok, _ in answers), answers)
        rss_after = node_rss_kib()
        rospy.loginfo("node RSS %d KiB before, %d KiB after 5000 commands; service answers %s",
                      rss_before, rss_after, ["%.3f s" % t for _, t in answers])
        self.assertLess(rss_after - rss_before, 20 * 1024, "memory stays bounded")


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "load", LoadTest)
