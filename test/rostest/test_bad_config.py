#!/usr/bin/env python3
"""Bad YAML stops the real node with one clear error naming the key and the value; so does a
share port another bus already listens on."""
import copy
import socket
import subprocess
import unittest

import rosparam
import rospy
import rostest

GOOD = {
    "port": "/tmp/modbus_rtu_rostest_bad_config/none",
    "baud": 9600,
    "devices": {"relays": {"type": "lc_relay8", "address": 255}},
}


def with_change(path, value):
    """GOOD with one key changed (value None removes it)."""
    cfg = copy.deepcopy(GOOD)
    node = cfg
    for key in path[:-1]:
        node = node[key]
    if value is None:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return cfg


CASES = [
    (with_change(["devices", "relays", "type"], "ld99"), ["devices/relays/type", "ld99"]),
    (with_change(["baud"], 9601), ["baud", "9601"]),
    (with_change(["parity"], "mark"), ["parity", "mark"]),
    (with_change(["devices", "relays", "address"], 0), ["devices/relays/address"]),
    (with_change(["devices", "pdu"], {"type": "yespeed_pdu", "address": 255}),
     ["address", "255"]),
    (with_change(["devices", "pdu"], {"type": "yespeed_pdu", "address": 248}),
     ["devices/pdu/address", "248"]),
    (with_change(["devices", "relays", "outputs"], ["pump", "bad-name"] + ["x%d" % i for i in range(6)]),
     ["devices/relays/outputs", "bad-name"]),
    (with_change(["devices", "relays", "poll_rate"], -1.0), ["devices/relays/poll_rate"]),
    (with_change(["devices", "relays", "colour"], "red"), ["devices/relays/colour", "unknown key"]),
    (with_change(["devices"], None), ["devices", "missing"]),
    (with_change(["stop_bits"], 3), ["stop_bits", "3"]),
    (with_change(["response_timeout"], "fast"), ["response_timeout", "fast"]),
    # Fail-safe keys (docs/failsafe.md).
    (with_change(["devices", "relays", "safe_state"], "maybe"), ["devices/relays/safe_state", "maybe"]),
    (with_change(["devices", "relays", "safe_state"], {"pumpx": "off"}),
     ["devices/relays/safe_state/pumpx", "no output channel"]),
    (with_change(["devices", "relays", "command_timeout"], 1.0),
     ["devices/relays/command_timeout/out0", "safe_state"]),
    (with_change(["devices", "relays", "on_restart"], "reboot"), ["devices/relays/on_restart", "reboot"]),
    (with_change(["devices", "relays", "on_start"], "now"), ["devices/relays/on_start", "now"]),
    (with_change(["devices", "relays", "heartbeat"], {"topic": "alive"}),
     ["devices/relays/heartbeat/timeout", "missing"]),
    (with_change(["heartbeat"], {"topic": "alive", "timeout": 0}), ["heartbeat/timeout", "outside"]),
    (with_change(["shutdown_timeout"], 120), ["shutdown_timeout", "outside"]),
    # Issue 24/8: an LD58A08 answers at 0xFF too: the LC board at its factory 255 must move.
    (with_change(["devices", "pwm_board"], {"type": "ld58a08", "address": 1}),
     ["devices/relays/address", "255 collides with the ld58a08 'pwm_board'",
      "Move 'relays' off 255"]),
    # Issue 24/6: fail-safe keys that would do nothing on a generic device.
    (with_change(["devices", "meter"], {"type": "generic", "address": 3, "safe_state": "off",
                                        "signals": [{"name": "a", "table": "coil",
                                                     "address": 0, "writable": True}]}),
     ["devices/meter/safe_state", "not for type generic", "safe_value"]),
    (with_change(["devices", "meter"], {"type": "generic", "address": 3, "signals": [
        {"name": "a", "table": "holding_register", "address": 0, "scale": 10, "writable": True,
         "max": 95, "safe_value": 95}]}),
     ["devices/meter/signals[0]/safe_value", "would be written as 100"]),
]


class BadConfigTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_bad_config")

    def test_good_config_starts(self):
        # The baseline must be valid, or the cases below would prove nothing.
        rosparam.upload_params("/good_case", GOOD)
        proc = subprocess.Popen(["rosrun", "modbus_rtu_driver", "modbus_rtu_bus", "__name:=good_case"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            out, _ = proc.communicate(timeout=4)
            self.fail("the node with a valid config exited (%s): %s" % (proc.returncode, out))
        except subprocess.TimeoutExpired:
            proc.terminate()
            proc.communicate(timeout=10)

    def test_each_bad_key_stops_the_node_naming_it(self):
        for i, (cfg, words) in enumerate(CASES):
            name = "bad_case_%d" % i
            rosparam.upload_params("/" + name, cfg)
            proc = subprocess.run(["rosrun", "modbus_rtu_driver", "modbus_rtu_bus", "__name:=" + name],
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                  timeout=20)
            self.assertNotEqual(proc.returncode, 0, "%s started with %r" % (name, cfg))
            errors = [l for l in proc.stdout.splitlines() if "invalid configuration" in l]
            self.assertEqual(len(errors), 1, proc.stdout)
            for w in words:
                self.assertIn(w, errors[0], "case %d: %r" % (i, cfg))

    def test_a_taken_share_port_stops_the_node_naming_share_listen(self):
        # Issue 33 item 2: a second bus left on the first's share/listen port (both on the
        # default 1502) stops at start with the key to change (docs/share.md, "Several buses").
        # The port is taken here by a socket of the test (bound to port 0: a free one).
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen(1)
            port = taken.getsockname()[1]
            cfg = copy.deepcopy(GOOD)
            cfg["share"] = {"listen": "127.0.0.1:%d" % port}
            # The check comes before the bus is touched: no on_start write is even tried.
            cfg["devices"]["relays"].update({"safe_state": "off", "on_start": "safe"})
            rosparam.upload_params("/second_bus", cfg)
            proc = subprocess.run(["rosrun", "modbus_rtu_driver", "modbus_rtu_bus",
                                   "__name:=second_bus"], stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True, timeout=30)
        self.assertNotEqual(proc.returncode, 0, proc.stdout)
        errors = [line for line in proc.stdout.splitlines() if "share/listen" in line]
        self.assertEqual(len(errors), 1, proc.stdout)
        self.assertIn("share/listen: 127.0.0.1:%d: address in use (another bus's share, or "
                      "another program, listens there): give each bus its own share/listen "
                      "port" % port, errors[0])
        self.assertNotIn("fail-safe start", proc.stdout,
                         "on_start wrote (or tried to) before the share's port was checked")


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "bad_config", BadConfigTest)
