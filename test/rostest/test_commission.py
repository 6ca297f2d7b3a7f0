#!/usr/bin/env python3
"""modbus_rtu_commission as a user runs it, against the simulator executable over a real pty.

Each test starts its own simulator (config, state file and frame log in a temp dir) so it can
power-cycle or restart it. The tool runs with a dead ROS master address: it needs none."""
import json
import os
import queue
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import rostest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from sim_control import SimControl  # noqa: E402  (test/sim_control.py)
from helpers import free_port  # noqa: E402  (below the ephemeral range, checked to bind)

PKG = "modbus_rtu_driver"



OK, BAD_ARGUMENTS, NOT_FOUND, REFUSED, BUS_ERROR, NOT_CONFIRMED = 0, 2, 3, 4, 5, 6


def executable(name):
    return subprocess.check_output(["catkin_find", "--first-only", "--libexec", PKG, name],
                                   text=True).strip()


class Simulator:
    """modbus_rtu_simulator with its own config and state file; every frame logged."""

    def __init__(self, workdir, devices, rtu_tcp=None):
        self.rtu_tcp = rtu_tcp  # also serve the line as an RTU-over-TCP gateway on this port
        self.dir = workdir
        self.link = os.path.join(workdir, "tty")
        self.config = os.path.join(workdir, "sim.yaml")
        self.state = os.path.join(workdir, "state.yaml")
        self.log_path = os.path.join(workdir, "frames.log")
        with open(self.config, "w") as f:
            f.write("baud: 9600\nparity: none\ndevices:\n")
            for dtype, address in devices:
                f.write("  - {type: %s, address: %d}\n" % (dtype, address))
        self.proc = None
        self.control = SimControl(self.link + ".ctl")
        self.start()

    def start(self):
        log = open(self.log_path, "a")
        self.proc = subprocess.Popen(
            [executable("modbus_rtu_simulator"), "--config", self.config, "--link", self.link,
             "--state-file", self.state, "--verbose"] +
            (["--rtu-tcp", str(self.rtu_tcp)] if self.rtu_tcp else []),
            stdout=log, stderr=subprocess.STDOUT)
        log.close()
        deadline = time.time() + 20
        while True:
            try:
                self.control.command("info")
                return
            except OSError:
                if time.time() > deadline or self.proc.poll() is not None:
                    raise RuntimeError("the simulator did not start; see " + self.log_path)
                time.sleep(0.05)

    def stop(self):
        """Stops the process (its frame log is complete afterwards)."""
        if self.proc and self.proc.poll() is None:
            self.proc.terminate()
            self.proc.wait(10)

    def frames_received(self):
        return self.control.frames()[0]

    def wait_all_answered(self, timeout=10):
        """Until every frame received has its reply on the line (late ones included)."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            received, answered, _ = self.control.frames()
            if answered == received:
                return
            time.sleep(0.02)
        raise AssertionError("the simulator still owes replies after %.0f s" % timeout)

    def devices(self):
        """{type: (address, baud, parity)}"""
        return {t: (a, b, p) for _, t, a, b, p in self.control.info()}

    def log(self):
        with open(self.log_path) as f:
            return f.read()


class CommissionTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="modbus_rtu_commission_")
        self.sim = None
        self.tool = executable("modbus_rtu_commission")
        # The tool needs no ROS master: point it at a port bound here and never listened on,
        # where a connection is refused whatever else runs on this machine.
        self.no_master = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.no_master.bind(("127.0.0.1", 0))
        self.env = dict(os.environ,
                        ROS_MASTER_URI="http://127.0.0.1:%d" % self.no_master.getsockname()[1])

    def tearDown(self):
        if self.sim:
            self.sim.stop()
        self.no_master.close()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def start_sim(self, devices, rtu_tcp=None):
        self.sim = Simulator(self.tmp, devices, rtu_tcp)

    def argv(self, args):
        port = self.sim.link if self.sim else "/nonexistent"
        if self.sim and self.sim.rtu_tcp:
            port = "rtu+tcp://127.0.0.1:%d" % self.sim.rtu_tcp
        return [self.tool, "--port", port] + args

    def run_tool(self, args, stdin=""):
        """(exit code, stdout, stderr)"""
        p = subprocess.run(self.argv(args), input=stdin, capture_output=True, text=True,
                           env=self.env, timeout=120)
        return p.returncode, p.stdout, p.stderr

    def ok(self, args, stdin=""):
        code, out, err = self.run_tool(args, stdin)
        self.assertEqual(code, OK, "%s -> %d\n%s%s" % (args, code, out, err))
        return out

    def scan(self, *args):
        """[(address, type, baud, parity)] found by a JSON scan."""
        code, out, err = self.run_tool(["--json", "scan"] + list(args))
        self.assertIn(code, (OK, NOT_FOUND), err)
        result = json.loads(out)
        self.assertTrue(result["complete"])
        return [(d["address"], d["type"], d["baud"], d["parity"]) for d in result["devices"]]

    def test_scan_finds_the_configured_devices_and_no_ghosts(self):
        self.start_sim([("lc_relay8", 255), ("ld58a08", 1), ("yespeed_pdu", 2)])
        # Parities stay "none": a pty cannot carry parity, so the simulator cannot tell them apart.
        self.assertEqual(self.scan("--addresses", "1-8,248-255", "--bauds", "9600,19200"),
                         [(1, "ld58a08", 9600, "none"), (2, "yespeed_pdu", 9600, "none"),
                          (255, "lc_relay8", 9600, "none")])
        out = self.ok(["scan", "--from", "1", "--to", "3"])
        self.assertEqual(out, "found ld58a08 at address 1, 9600 8N1\n"
                              "found yespeed_pdu at address 2, 9600 8N1\n2 device(s) found\n")
        out = self.ok(["scan", "--first"])
        self.assertEqual(out, "found ld58a08 at address 1, 9600 8N1\n1 device(s) found\n")
        code, out, err = self.run_tool(["scan", "--addresses", "10-12"])
        self.assertEqual(code, NOT_FOUND)
        self.assertIn("0 device(s) found", out)

    def test_scan_stops_early_on_ctrl_c_and_still_lists_what_it_found(self):
        self.start_sim([("ld58a08", 1), ("yespeed_pdu", 2)])
        proc = subprocess.Popen(self.argv(["scan"]), stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, env=self.env)
        lines = [proc.stdout.readline(), proc.stdout.readline()]
        self.assertEqual(lines, ["found ld58a08 at address 1, 9600 8N1\n",
                                 "found yespeed_pdu at address 2, 9600 8N1\n"])
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)  # the rest of 1-255 would take ~20 s more
        self.assertEqual(proc.returncode, OK, err)
        self.assertEqual(out, "2 device(s) found (scan stopped early)\n")
        self.assertIn("scanning 9600 8N1 from address 1", err)  # progress on stderr

    def test_ld58a08_address_change_answers_at_the_new_address_only(self):
        self.start_sim([("ld58a08", 1)])
        code, _, err = self.run_tool(
            ["set-address", "--type", "ld58a08", "--address", "1", "9"], stdin="n\n")
        self.assertEqual(code, NOT_CONFIRMED)
        self.assertIn("It answers only at the new address", err)
        self.assertEqual(self.sim.devices()["ld58a08"][0], 1)

        out = self.ok(["set-address", "--type", "ld58a08", "--address", "1", "9"], stdin="y\n")
        self.assertEqual(out, "ld58a08 address changed from 1 to 9; it answers at 9\n")
        self.assertEqual(self.sim.devices()["ld58a08"][0], 9)
        self.assertEqual(self.run_tool(["read", "--address", "1", "coil", "0"])[0], NOT_FOUND)
        self.assertEqual(self.ok(["--json", "read", "--address", "9", "holding_register", "0xFD"]),
                         '{"ok":true,"address":9,"table":"holding_register","start":253,"values":[9]}\n')
        # Address unknown: through 0xFF, as the manual prints it.
        self.assertEqual(self.ok(["get-address", "--type", "ld58a08"]), "ld58a08 address: 9\n")
        self.ok(["--yes", "set-address", "--type", "ld58a08", "4"])
        self.assertEqual(self.scan("--addresses", "1-10"), [(4, "ld58a08", 9600, "none")])
        self.sim.stop()
        log = self.sim.log()
        # The reply to the change still came from the old address; then it moved.
        self.assertIn("tx 01 06 00 FD 00 09", log)
        self.assertIn("rx FF 03 00 FD 00 01 00 24", log)
        self.assertIn("tx FF 06 00 FD 00 04", log)

    def test_lc_board_address_change_through_address_zero(self):
        self.start_sim([("lc_relay8", 255)])
        self.assertEqual(self.ok(["get-address", "--type", "lc_relay8"]),
                         "lc_relay8 address: 255\n")
        code, _, err = self.run_tool(["set-address", "--type", "lc_relay8", "200"])  # no stdin
        self.assertEqual(code, NOT_CONFIRMED)
        self.assertIn("only this board may be connected", err)
        out = self.ok(["--yes", "set-address", "--type", "lc_relay8", "--address", "255", "200"])
        self.assertEqual(out, "lc_relay8 address changed from 255 to 200; it answers at 200\n")
        self.assertEqual(self.run_tool(["read", "--address", "255", "coil", "0", "8"])[0],
                         NOT_FOUND)
        self.ok(["read", "--address", "200", "coil", "0", "8"])
        self.assertEqual(self.scan("--addresses", "199-201,255"),
                         [(200, "lc_relay8", 9600, "none")])
        self.ok(["--yes", "set-address", "--type", "lc_relay8", "255"])
        self.sim.stop()
        self.assertIn("rx 00 10 00 00 00 01 02 00 FF EB 80", self.sim.log())  # the manual's frame

    def test_baud_change_takes_effect_after_a_power_cycle_and_survives_a_restart(self):
        # The LC board comes first: the simulator gives 0xFF to the first device that claims
        # it, and its LD58A08 claims every register from 0xFA up there, the LC's 0x03E8 too.
        self.start_sim([("lc_relay8", 255), ("ld58a08", 1)])
        out = self.ok(["--yes", "set-baud", "--type", "ld58a08", "--address", "1", "19200"])
        self.assertIn("It takes effect after the device is powered off and on", out)
        self.ok(["--yes", "set-baud", "--type", "lc_relay8", "--address", "255", "4"])
        scan = ["--addresses", "1,255", "--bauds", "9600,19200"]
        self.assertEqual(self.scan(*scan), [(1, "ld58a08", 9600, "none"),
                                            (255, "lc_relay8", 9600, "none")])
        self.sim.control.power_cycle()
        after = [(1, "ld58a08", 19200, "none"), (255, "lc_relay8", 19200, "none")]
        self.assertEqual(self.scan(*scan), after)
        self.sim.stop()  # the state file keeps what the boards stored
        self.sim.start()
        self.assertEqual(self.scan(*scan), after)
        self.assertIn("19200 baud (code 4)", self.ok(["--baud", "19200", "get-baud", "--type",
                                                      "ld58a08", "--address", "1"]))

    def test_parity_is_stored_and_taken_at_power_on(self):
        self.start_sim([("ld58a08", 1)])
        out = self.ok(["--yes", "set-parity", "--address", "1", "even"])
        self.assertIn("powered off and on; then reach it with --parity even", out)
        self.assertEqual(self.sim.control.get("1", "holding_register", 0xFF), [1])
        self.assertEqual(self.ok(["get-parity", "--address", "1"]),
                         "ld58a08 at address 1, parity: even\n")  # still answers at 8N1
        self.assertEqual(self.sim.devices()["ld58a08"][2], "N")
        self.sim.control.power_cycle()
        self.assertEqual(self.sim.devices()["ld58a08"][2], "E")

    def test_bad_values_are_refused_before_anything_is_sent(self):
        self.start_sim([("lc_relay8", 255), ("ld58a08", 1), ("yespeed_pdu", 2)])
        before = self.sim.frames_received()
        cases = [
            (["set-address", "--type", "ld58a08", "--address", "1", "0"], "new address: '0'"),
            (["set-address", "--type", "ld58a08", "--address", "1", "249"], "outside 1-248"),
            (["set-address", "--type", "lc_relay8", "256"], "new address: '256' is outside 1-255"),
            (["set-address", "--type", "ld58a08", "--address", "249", "5"], "--address: '249'"),
            (["set-baud", "--type", "ld58a08", "--address", "1", "9"], "neither a code 0-7"),
            (["set-baud", "--type", "lc_relay8", "--address", "255", "115200"], "code 2-4"),
            (["set-parity", "--address", "1", "mark"], "parity: 'mark' is not one of none, even, odd"),
            (["set-return-delay", "--address", "1", "1001"], "'1001' is outside 0-1000"),
            (["set-return-delay", "--address", "1", "100"], "not a multiple of 40 ms"),
            (["read", "--address", "1", "holding_register", "0", "126"], "count: '126' is outside 1-125"),
            (["write", "--address", "255", "coil", "0", "2"], "value: '2' is outside 0-1"),
            (["--baud", "9601", "scan"], "--baud: '9601'"),
            (["scan", "--parities", "mark"], "--parities: 'mark'"),
        ]
        for args, message in cases:
            code, out, err = self.run_tool(args + ["--yes"] if args[0] != "scan" else args)
            self.assertEqual(code, BAD_ARGUMENTS, args)
            self.assertIn(message, err, args)
            self.assertEqual(out, "", args)
        code, out, _ = self.run_tool(["--json", "set-parity", "--address", "1", "mark"])
        self.assertEqual(json.loads(out), {"ok": False, "exit": BAD_ARGUMENTS,
                                           "error": "parity: 'mark' is not one of none, even, odd"})
        self.assertEqual(self.sim.frames_received(), before, "a refused command sent a frame")

    def test_exit_codes_tell_no_answer_refusal_and_bus_errors_apart(self):
        self.start_sim([("ld58a08", 1), ("yespeed_pdu", 2)])
        self.assertEqual(self.run_tool(["read", "--address", "9", "coil", "0"])[0], NOT_FOUND)
        code, _, err = self.run_tool(["read", "--address", "1", "holding_register", "5"])
        self.assertEqual(code, REFUSED)
        self.assertIn("illegal data address", err)
        self.sim.control.fail("2")
        self.assertEqual(self.run_tool(["read", "--address", "2", "coil", "0"])[0], REFUSED)
        self.sim.control.corrupt("1", 1)
        code, out, _ = self.run_tool(["--json", "read", "--address", "1", "coil", "0"])
        self.assertEqual(code, BUS_ERROR)
        self.assertEqual(json.loads(out)["exit"], BUS_ERROR)
        self.ok(["read", "--address", "1", "coil", "0"])  # the next reply is clean again
        sim, self.sim = self.sim, None  # --port /nonexistent
        self.assertEqual(self.run_tool(["info", "--address", "1"])[0], BUS_ERROR)
        self.sim = sim

    def test_return_delay_needs_a_longer_scan_timeout(self):
        self.start_sim([("ld58a08", 1)])
        self.ok(["--yes", "set-return-delay", "--address", "1", "200"])
        self.assertEqual(self.scan("--addresses", "1"), [])  # 81 ms per address: too short
        self.sim.wait_all_answered()  # the late reply must not meet the next scan
        self.assertEqual(self.scan("--timeout", "0.6", "--addresses", "1"),
                         [(1, "ld58a08", 9600, "none")])
        self.assertIn("return delay: 200 ms", self.ok(["info", "--address", "1"]))
        self.ok(["--yes", "set-return-delay", "--address", "1", "0"])
        self.assertEqual(self.scan("--addresses", "1"), [(1, "ld58a08", 9600, "none")])

    def test_factory_reset_through_0xff(self):
        self.start_sim([("ld58a08", 1)])
        self.ok(["--yes", "set-address", "--type", "ld58a08", "--address", "1", "5"])
        self.ok(["--yes", "set-parity", "--address", "5", "odd"])
        self.assertEqual(self.run_tool(["factory-reset"], stdin="")[0], NOT_CONFIRMED)
        self.assertEqual(self.sim.devices()["ld58a08"][0], 5)
        self.assertIn("factory settings restored", self.ok(["--yes", "factory-reset"]))
        self.assertIn("stored parity: none", self.ok(["info", "--address", "1"]))
        self.sim.stop()
        self.assertIn("rx FF 06 00 FB 00 00 ED E5", self.sim.log())  # the manual's frame

    def test_pdu_limits(self):
        # Issue #13/9: get-limits / set-limits, checked on the register values written.
        self.start_sim([("lc_relay8", 255), ("yespeed_pdu", 2)])
        self.assertEqual(self.ok(["get-limits", "--address", "2"]),
                         "yespeed_pdu at address 2, limits: over-voltage 250.0 V, "
                         "under-voltage 200.0 V, over-current 16.00 A\n")
        before = self.sim.frames_received()
        for args, message in [(["--over-voltage", "180.00001"], "(register 1800)"),
                              (["--over-current", "19.999999"], "(register 2000)")]:
            code, out, err = self.run_tool(["--yes", "set-limits", "--address", "2"] + args)
            self.assertEqual(code, BAD_ARGUMENTS, err)
            self.assertIn(message, err)
        self.assertEqual(self.sim.frames_received(), before, "a refused command sent a frame")
        code, _, err = self.run_tool(["set-limits", "--address", "2", "--over-voltage", "260"])
        self.assertEqual(code, NOT_CONFIRMED, err)
        self.assertEqual(self.sim.control.get("2", "holding_register", 0, 3), [2500, 2000, 1600])
        # One limit: the others stay as the PDU holds them.
        out = self.ok(["--yes", "set-limits", "--address", "2", "--over-voltage", "260"])
        self.assertIn("limits set to over-voltage 260.0 V, under-voltage 200.0 V", out)
        self.assertEqual(self.sim.control.get("2", "holding_register", 0, 3), [2600, 2000, 1600])
        # Not above the PDU's own under-voltage: refused before the write.
        code, _, err = self.run_tool(["--yes", "set-limits", "--address", "2",
                                      "--over-voltage", "190"])
        self.assertEqual(code, BAD_ARGUMENTS, err)
        self.assertIn("must be above under_voltage (200.0 V)", err)
        self.assertEqual(self.sim.control.get("2", "holding_register", 0, 3), [2600, 2000, 1600])
        self.sim.stop()
        self.assertIn("rx 02 10 00 00 00 03 06 0A 28 07 D0 06 40", self.sim.log())

    def test_ld58a08_address_read_answered_by_an_lc_board_hints_at_its_type(self):
        self.start_sim([("lc_relay8", 255)])
        code, _, err = self.run_tool(["get-address", "--type", "ld58a08"])
        self.assertEqual(code, REFUSED, err)
        self.assertIn("illegal data address (02)", err)
        self.assertIn("try --type lc_relay8", err)

    def test_two_lc_boards_collide_at_address_zero(self):
        # Issue #13/8: what "alone on the bus" prevents. Both boards answer the address read at
        # 0, the replies collide, and the tool stops before it writes anything.
        self.start_sim([("lc_relay8", 255), ("lc_relay8", 254)])
        code, _, err = self.run_tool(["get-address", "--type", "lc_relay8"])
        self.assertEqual(code, BUS_ERROR, err)
        self.assertIn("two devices answering at once", err)
        code, _, err = self.run_tool(["--yes", "set-address", "--type", "lc_relay8", "7"])
        self.assertEqual(code, BUS_ERROR, err)
        self.assertEqual([a for _, _, a, _, _ in self.sim.control.info()], [255, 254])
        self.sim.stop()
        self.assertNotIn("rx 00 10", self.sim.log(), "the tool wrote an address")

    def test_write_read_and_watch(self):
        self.start_sim([("lc_relay8", 255), ("ld58a08", 1)])
        self.ok(["write", "--address", "255", "coil", "0", "1", "0", "1"])
        self.assertEqual(self.sim.control.get("255", "coil", 0, 3), [1, 0, 1])
        self.ok(["write", "--address", "1", "holding_register", "0x80", "9"])
        self.assertEqual(self.sim.control.get("1", "coil", 0, 4), [1, 0, 0, 1])
        self.assertEqual(json.loads(self.ok(["--json", "read", "--address", "1", "coil", "0",
                                             "4"]))["values"], [1, 0, 0, 1])

        proc = subprocess.Popen(self.argv(["watch", "--address", "255", "discrete_input", "0",
                                           "8", "--interval", "0.05"]),
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=self.env)
        lines = queue.Queue()
        threading.Thread(target=lambda: [lines.put(l) for l in proc.stdout], daemon=True).start()
        try:
            first = lines.get(timeout=10)
            self.assertIn("discrete_input 0: 0, discrete_input 1: 0", first)
            self.sim.control.set("255", "discrete_input", 1, 1)
            change = lines.get(timeout=10)
            self.assertRegex(change, r"^\+[0-9.]+ s  discrete_input 1: 0 -> 1\n$")
            time.sleep(0.3)  # several more polls: nothing changed, nothing printed
            self.assertTrue(lines.empty())
        finally:
            proc.send_signal(signal.SIGINT)
            proc.wait(10)
        self.assertEqual(proc.returncode, OK)

    def test_through_an_rtu_over_tcp_gateway(self):
        self.start_sim([("lc_relay8", 255), ("yespeed_pdu", 2)], rtu_tcp=free_port())
        self.assertEqual(self.scan("--addresses", "1-3,255"),
                         [(2, "yespeed_pdu", 9600, "none"), (255, "lc_relay8", 9600, "none")])
        self.ok(["write", "--address", "255", "coil", "0", "1", "1"])
        self.assertEqual(self.sim.control.get("255", "coil", 0, 2), [1, 1])
        self.assertEqual(self.ok(["get-address", "--type", "lc_relay8"]),  # through address 0
                         "lc_relay8 address: 255\n")
        p = subprocess.run([self.tool, "--port", "tcp://127.0.0.1", "scan"], capture_output=True,
                           text=True, env=self.env, timeout=60)
        self.assertEqual(p.returncode, BAD_ARGUMENTS)
        self.assertIn("--port: 'tcp://127.0.0.1' is not tcp://HOST:PORT", p.stderr)


if __name__ == "__main__":
    rostest.rosrun(PKG, "commission", CommissionTest)
