#!/usr/bin/env python3
"""The shell examples of README.md and docs/*.md, run as written against the simulator and a
demo brought up by this test; a command that fails, or whose output lacks what it should
show, fails the test.

The docs stay plain: this file keeps, per doc file, which ```sh blocks run (by their index
among the file's ```sh blocks) and an expectation per command; every other ```sh block is
listed in NOT_RUN with the reason. A new or changed block fails the test until it is
classified here. The only rewrites are paths and ports the test chooses at run time
(SUBSTITUTE below), so that a user's demo or share on this machine is never touched."""
import os
import re
import shutil
import subprocess
import unittest

import rospy
import rostest
import yaml

import user_paths as up
from helpers import wait_until
from sim_control import SimControl

DOCS = ["README.md"] + sorted("docs/" + f for f in os.listdir(os.path.join(up.REPO, "docs"))
                             if f.endswith(".md"))


def ok(*contains):
    """The command exits 0 and its output holds each text."""
    return {"kind": "exit0", "contains": list(contains)}


def streams(*contains):
    """The command runs until stopped (rostopic echo, mbpoll, watch): its output shows each
    text, then the test stops it as a user's Ctrl-C would."""
    return {"kind": "stream", "contains": list(contains)}


def background(*contains):
    """Runs beside the block's later commands (the simulator), stopped at the block's end."""
    return {"kind": "background", "contains": list(contains)}


def sets_up():
    """A line that sets the shell up for the next ones (source, VAR=...)."""
    return {"kind": "setup"}


# Blocks not run, by (file, index): why.
NOT_RUN = {
    ("README.md", 0): "builds and runs everything: scripts/fresh_check.sh runs both commands",
    ("README.md", 1): "a catkin workspace from a clone with rosdep (needs the network): the "
                      "steps scripts/fresh_check.sh and the test command run in their own way",
    ("README.md", 3): "bus.launch with the user's file: test_launch_files.py runs this very "
                      "command for every config/ example and launch file",
    ("docs/troubleshooting.md", 0): "needs a USB serial adapter",
    ("docs/share.md", 1): "two buses' shares on 1502 and 1503: test_two_buses.py brings up "
                          "launch/two_bus_example.launch with two shares on ports of its own "
                          "and reads each bus through its share",
}


class DocCommandsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_doc_commands")
        cls.dir = up.scratch_dir("modbus_rtu_docs_")
        cls.env = dict(os.environ)
        if "MODBUS_RTU_WS" not in cls.env:  # the workspace this test runs from
            devel = [p for p in os.environ.get("CMAKE_PREFIX_PATH", "").split(":")
                     if p.endswith("/devel")]
            cls.env["MODBUS_RTU_WS"] = os.path.dirname(devel[0])

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    # -- the docs' blocks ------------------------------------------------------------------

    @staticmethod
    def blocks(doc):
        with open(os.path.join(up.REPO, doc)) as f:
            text = f.read()
        return [m.group(1) for m in re.finditer(r"^```sh\n(.*?)^```", text, re.S | re.M)]

    @staticmethod
    def commands(block):
        """The block's commands: one per line, backslash continuations joined."""
        return [c.strip() for c in block.replace("\\\n", " ").splitlines() if c.strip()]

    def test_every_block_is_run_or_says_why_not(self):
        run = {(doc, index) for doc, index, _ in self.RUN}
        for doc in DOCS:
            for index, _ in enumerate(self.blocks(doc)):
                self.assertTrue((doc, index) in run or (doc, index) in NOT_RUN,
                                "%s: ```sh block %d is neither run by %s nor in NOT_RUN"
                                % (doc, index, os.path.basename(__file__)))

    def run_block(self, doc, index, expectations, substitute):
        """Runs the block's commands in order, each in bash from the repository root after
        the block's setup lines. `expectations` maps a command's first words (as the doc has
        them) to an expectation, in the block's order."""
        block = self.commands(self.blocks(doc)[index])
        self.assertEqual(len(block), len(expectations),
                         "%s block %d has %d commands, the test expects %d: %s"
                         % (doc, index, len(block), len(expectations), block))
        setup = []
        running = []
        try:
            for command, (start, expect) in zip(block, expectations):
                self.assertTrue(command.startswith(start),
                                "%s block %d: '%s' where the test expects '%s...'"
                                % (doc, index, command, start))
                for old, new in substitute.items():
                    command = command.replace(old, new)
                command = expect.get("replace", command)
                if expect["kind"] == "setup":
                    setup.append(command)
                    continue
                if "before" in expect:
                    expect["before"]()
                script = "set -e\n" + "\n".join(setup + [command])
                proc = up.Process(["bash", "-c", script], self.dir,
                                  "cmd%d" % len(os.listdir(self.dir)), env=self.env,
                                  cwd=up.REPO, stdin=expect.get("stdin"))
                running.append(proc)  # stopped at the end even when a check below fails
                what = "%s block %d: %s" % (doc, index, command)
                if expect["kind"] == "exit0":
                    code = proc.wait_exit(120)
                    self.assertEqual(code, 0, "%s -> exit %s\n%s" % (what, code, proc.output()))
                    proc.stop()
                else:
                    wait_until(lambda: all(c in proc.output() for c in expect["contains"])
                               or not proc.running(), 60,
                               "%s to show %s (output: %r)"
                               % (what, expect["contains"], proc.output()[-400:]))
                    if expect["kind"] == "stream":
                        self.assertTrue(proc.running(), "%s ended:\n%s" % (what, proc.output()))
                        proc.stop()
                for text in expect["contains"]:
                    self.assertIn(text, proc.output(), what)
                if "after" in expect:
                    expect["after"]()
                rospy.loginfo("ran %s", what)
        finally:
            for proc in running:
                proc.stop()

    # -- README.md -------------------------------------------------------------------------

    def test_readme_quick_tour_against_the_demo(self):
        link = os.path.join(self.dir, "demo", "ttySIM")
        os.makedirs(os.path.dirname(link))
        demo = up.roslaunch(self.dir, "demo", "demo.launch", "link:=" + link)
        sim = SimControl(link + ".ctl")
        try:
            up.wait_for_file(link + ".ctl", 30, "the demo's simulator", demo)
            wait_until(lambda: not demo.running() or
                       "/modbus_bus/pdu/set_limits" in subprocess.run(
                           ["rosservice", "list"], capture_output=True, text=True).stdout,
                       60, "the demo's services")
            pulse_seen = []
            self.run_block("README.md", 2, [
                ("source ", sets_up()),
                ("rostopic echo /modbus_bus/relays/outputs", streams("names:", "pump", "---")),
                ("rosservice call /modbus_bus/relays/pump/set", dict(
                    ok("success: True"), after=lambda: self.assertEqual(
                        sim.get(8, "coil", 0), [1]))),
                ("rostopic pub -1 /modbus_bus/relays/lamp/command", dict(
                    ok(), after=lambda: wait_until(lambda: sim.get(8, "coil", 2) == [1], 10,
                                                   "the lamp (coil 2) on"))),
                ("rosservice call /modbus_bus/relays/pulse", dict(
                    ok("success: True"),
                    after=lambda: pulse_seen.append(sim.get(8, "coil", 1)))),
                ("rosservice call /modbus_bus/relays/set_outputs", dict(
                    ok("success: True"), after=lambda: self.assertEqual(
                        sim.get(8, "coil", 3), [1]))),
                ("rosservice call /modbus_bus/pwm_board/set_pwm \"{channel: 0",
                 ok("success: True")),
                ("rosservice call /modbus_bus/pwm_board/set_pwm \"{channel: 6",
                 ok("success: True")),
                ("rostopic echo /modbus_bus/pwm_board/pwm", streams("running: True", "---")),
                ("rostopic echo /modbus_bus/pdu/telemetry", streams("voltage:", "---")),
                ("rosservice call /modbus_bus/pdu/set_limits", ok("success: True")),
                ("rostopic echo /diagnostics", streams("modbus_bus", "---")),
            ], {})
            self.assertEqual(pulse_seen, [[1]], "the pulse closed relay #2")
        finally:
            demo.stop()

    def commissioning_sim(self):
        """The README's commissioning examples' boards: LC relay 255, LD58A08 1, PDU 3."""
        link = os.path.join(self.dir, "commission", "ttyUSB0")
        os.makedirs(os.path.dirname(link))
        config = os.path.join(self.dir, "commission", "sim.yaml")
        with open(config, "w") as f:
            yaml.safe_dump({"baud": 9600, "devices": [
                {"type": "lc_relay8", "address": 255}, {"type": "ld58a08", "address": 1},
                {"type": "yespeed_pdu", "address": 3}]}, f)
        return up.start_simulator(config, link, os.path.dirname(link)), link

    def commission(self, link, *args):
        out = subprocess.run(["rosrun", "modbus_rtu_driver", "modbus_rtu_commission", "--port",
                              link] + list(args), capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stdout + out.stderr)

    def test_readme_commissioning_against_the_simulator(self):
        sim_process, link = self.commissioning_sim()
        sim = SimControl(link + ".ctl")
        try:
            yes = {"stdin": "y\n"}
            # The scan of every baud and address (minutes) is the only one not run: a scan of
            # the same form over addresses 1-3 stands in for it.
            subst = {"/dev/ttyUSB0": link}
            quick_scan = ("rosrun modbus_rtu_driver modbus_rtu_commission --port %s scan "
                          "--bauds all --from 1 --to 3" % link)
            self.run_block("README.md", 4, [
                ("rosrun modbus_rtu_driver modbus_rtu_commission --port /dev/ttyUSB0 scan",
                 dict(ok("device(s) found"), replace=quick_scan)),
                ("rosrun modbus_rtu_driver modbus_rtu_commission --port /dev/ttyUSB0 set-address --type lc_relay8",
                 dict(ok(), **yes)),
                ("rosrun modbus_rtu_driver modbus_rtu_commission --port /dev/ttyUSB0 set-address --type ld58a08",
                 dict(ok(), **yes)),
                ("rosrun modbus_rtu_driver modbus_rtu_commission --port /dev/ttyUSB0 set-baud",
                 dict(ok(), before=sim.power_cycle, **yes)),
                ("rosrun modbus_rtu_driver modbus_rtu_commission --port /dev/ttyUSB0 --json read",
                 ok('"values"')),
                # The board set to 7 above goes back to 255 first, where this example finds it.
                ("rosrun modbus_rtu_driver modbus_rtu_commission --port /dev/ttyUSB0 watch --address 255",
                 dict(streams("discrete_input 7: 0"), before=lambda: self.commission(
                     link, "--yes", "set-address", "--type", "lc_relay8", "255"))),
                ("rosrun modbus_rtu_driver modbus_rtu_commission --port /dev/ttyUSB0 get-limits",
                 ok("limits: over-voltage")),
                ("rosrun modbus_rtu_driver modbus_rtu_commission --port /dev/ttyUSB0 set-limits",
                 ok()),
            ], subst)
        finally:
            sim_process.stop()

    # -- docs/simulator.md -----------------------------------------------------------------

    def test_simulator_md(self):
        sim_dir = os.path.join(self.dir, "sim")
        os.makedirs(sim_dir)
        self.run_block("docs/simulator.md", 0, [
            ("WS=", sets_up()),
            ("$WS/devel/lib/modbus_rtu_driver/modbus_rtu_simulator",
             background("simulator ready on " + sim_dir + "/ttySIM")),
            ("mbpoll -m rtu", streams("[1]:", "[5]:")),
            ("python3 test/sim_control.py", ok("ok\n")),
        ], {"/tmp/sim/": sim_dir + "/"})

    # -- docs/share.md ---------------------------------------------------------------------

    def test_share_md_against_a_shared_demo_bus(self):
        link = os.path.join(self.dir, "share", "ttySIM")
        os.makedirs(os.path.dirname(link))
        sim_process = up.start_simulator(os.path.join(up.REPO, "config", "simulator.yaml"),
                                         link, os.path.dirname(link))
        port = up.free_port()
        with open(os.path.join(up.REPO, "config", "demo.yaml")) as f:
            config = yaml.safe_load(f)
        config["share"] = {"listen": "127.0.0.1:%d" % port}
        path = os.path.join(self.dir, "share", "bus.yaml")
        with open(path, "w") as f:
            yaml.safe_dump(config, f)
        bus = up.roslaunch(os.path.dirname(link), "bus", "bus.launch", "config:=" + path,
                           "port:=" + link)
        sim = SimControl(link + ".ctl")
        try:
            up.check_device_answers("/modbus_bus", "relays", config["devices"]["relays"],
                                    up.REPO, bus)
            sim.set(8, "coil", 2, 0)
            self.run_block("docs/share.md", 0, [
                ("mbpoll -m tcp -p 1502 -a 8 -t 0 -r 0", ok("[0]:", "[7]:")),
                ("mbpoll -m tcp -p 1502 -a 8 -t 0 -r 2", dict(ok(), after=lambda: self.assertEqual(
                    sim.get(8, "coil", 2), [1], "relay #3 on"))),
            ], {"-p 1502": "-p %d" % port})
        finally:
            bus.stop()
            sim_process.stop()

    RUN = [("README.md", 2, test_readme_quick_tour_against_the_demo),
           ("README.md", 4, test_readme_commissioning_against_the_simulator),
           ("docs/simulator.md", 0, test_simulator_md),
           ("docs/share.md", 0, test_share_md_against_a_shared_demo_bus)]


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "doc_commands", DocCommandsTest)
