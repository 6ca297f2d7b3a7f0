#!/usr/bin/env python3
"""Every launch file in launch/ and every bus example in config/ brought up as the README shows
it (`roslaunch modbus_rtu_driver bus.launch config:=... port:=...`, `demo.launch`,
`robot_example.launch`) against a simulator on a pty, each device answering: a state topic seen
and a service called with success. And bus.launch started twice on one master with different
files: nothing of the first file is left on the parameter server."""
import os
import shutil
import socket
import unittest

import rospy
import rostest
import yaml

from std_msgs.msg import Bool

import user_paths as up
from helpers import wait_until

# The launch files this test brings up; a new one must be added here (and brought up).
# two_bus_example.launch: brought up by test_two_buses.py (its bags and their plot too).
COVERED_LAUNCH_FILES = {"bus.launch", "demo.launch", "robot_example.launch",
                        "two_bus_example.launch"}


def bus_configs():
    """config/*.yaml that configure a bus node (simulator configs list their devices)."""
    out = []
    for name in sorted(os.listdir(os.path.join(up.REPO, "config"))):
        path = os.path.join(up.REPO, "config", name)
        if not name.endswith(".yaml"):
            continue
        with open(path) as f:
            config = yaml.safe_load(f)
        if isinstance(config.get("devices"), list):
            continue  # a simulator configuration: brought up as one below
        out.append(path)
    return out


class LaunchFilesTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_launch_files")
        cls.dir = up.scratch_dir("modbus_rtu_launch_")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def bring_up(self, tag, launch_args, namespace, devices, config_dir, sim_config=None,
                 link=None):
        """Starts the simulator (when given) and roslaunch; checks every device answers."""
        log_dir = os.path.join(self.dir, tag)
        os.makedirs(log_dir)
        sim = up.start_simulator(sim_config, link, log_dir) if sim_config else None
        launch = up.roslaunch(log_dir, "roslaunch", *launch_args)
        try:
            answers = [up.check_device_answers(namespace, name, device, config_dir, launch)
                       for name, device in devices.items()]
            rospy.loginfo("%s: %s", tag, "; ".join(answers))
        except AssertionError as e:
            # What the node said is what tells why (a CI run once timed out here, unseen since).
            raise AssertionError("%s\nroslaunch's output, last lines:\n%s"
                                 % (e, launch.tail())) from None
        finally:
            launch.stop()
            if sim:
                sim.stop()
        self.stopped_output = launch.output()
        return answers

    def test_every_launch_file_is_covered(self):
        here = {f for f in os.listdir(os.path.join(up.REPO, "launch")) if f.endswith(".launch")}
        self.assertEqual(here, COVERED_LAUNCH_FILES, "launch files without a bring-up test")

    def test_bus_launch_with_every_example_config(self):
        configs = bus_configs()
        self.assertGreaterEqual(len(configs), 7)
        used_sims = set()
        failed = []  # every example tried, each failure named (rosunit drops subTest's)
        for path in configs:
            name = os.path.basename(path)[:-len(".yaml")]
            try:
                config, devices = up.bus_devices(path)
                link = os.path.join(self.dir, name + "_tty")
                if config.get("role") == "slave":
                    self.bring_up_slave(path, link)
                    continue
                sim_config = up.simulator_config_for(path, self.dir)
                used_sims.add(os.path.basename(sim_config))
                self.bring_up(name, ["bus.launch", "config:=" + path, "port:=" + link],
                              "/modbus_bus", devices, os.path.dirname(path), sim_config, link)
            except AssertionError as e:
                failed.append("config/%s.yaml: %s" % (name, e))
        self.assertEqual(failed, [], "\n\n".join(failed))
        # The simulator's own examples were brought up, each with the bus it simulates.
        sims = {f for f in os.listdir(os.path.join(up.REPO, "config"))
                if f.startswith("simulator") and f.endswith(".yaml")}
        self.assertEqual(used_sims & sims, sims)

    def bring_up_slave(self, path, link):
        """The slave role through bus.launch, with the DM500 master simulator on the pty: the
        master reads what ROS set and writes a coil that ROS sees."""
        log_dir = os.path.join(self.dir, "slave")
        os.makedirs(log_dir)
        script = os.path.join(log_dir, "dm500.script")
        report = os.path.join(log_dir, "report.txt")
        with open(script, "w") as f:
            f.write("wait_ready 1 within 30\n"
                    "wait_holding_register 1 5 1 equals 42 within 60\n"
                    "write_coils 1 6 12 03 04\n")
        dm500 = up.Process(["rosrun", "modbus_rtu_driver", "modbus_rtu_dm500_sim", "--link", link,
                            "--script", script, "--report", report], log_dir, "dm500")
        up.wait_for_file(link, 20, "the DM500 simulator's pty " + link, dm500)
        launch = up.roslaunch(log_dir, "roslaunch", "bus.launch", "config:=" + path,
                              "port:=" + link)
        spindle = []
        sub = rospy.Subscriber("/modbus_bus/coil/spindle_ready", Bool,
                               lambda m: spindle.append(m.data))
        try:
            from modbus_rtu_driver.srv import SetRegisters

            def alive():
                if not launch.running():
                    raise AssertionError("roslaunch exited (%s):\n%s"
                                         % (launch.proc.returncode, launch.tail()))
            res = up.call("/modbus_bus/set_holding_register", SetRegisters, alive, 5, [42])
            self.assertTrue(res.success, res.message)
            wait_until(lambda: alive() or (spindle and spindle[-1]), 60,
                       "coil 6 (spindle_ready) written by the DM500 on /modbus_bus/coil/")
            self.assertIsNotNone(dm500.wait_exit(30), "the DM500 script did not end")
            with open(report) as f:
                text = f.read()
            self.assertNotIn("FAIL", text, text)
        finally:
            sub.unregister()
            launch.stop()
            dm500.stop()

    def test_demo_launch(self):
        link = os.path.join(self.dir, "demo_tty")
        config, devices = up.bus_devices(os.path.join(up.REPO, "config", "demo.yaml"))
        # link:= keeps this run off /tmp/modbus_rtu_demo, where a user's demo may be running.
        self.bring_up("demo_launch", ["demo.launch", "link:=" + link], "/modbus_bus", devices,
                      os.path.join(up.REPO, "config"))
        # Stopped as Ctrl-C stops it (SIGINT to roslaunch, the simulator and the node at once):
        # the node's shutdown safe writes reach the simulator before it goes (issue 48 item 4).
        up.assert_shutdown_safe_writes_confirmed(self, self.stopped_output, ["relays"])

    def test_robot_example_launch(self):
        link = os.path.join(self.dir, "robot_tty")
        example = os.path.join(up.REPO, "config", "bus_example.yaml")
        config, devices = up.bus_devices(example)
        self.bring_up("robot_example_launch", ["robot_example.launch", "port:=" + link], "/my_robot/io_bus",
                      devices, os.path.join(up.REPO, "config"),
                      up.simulator_config_for(example, self.dir), link)

    def test_bus_launch_respawn_wins_over_required(self):
        # roslaunch refuses a node that is both required and respawned: respawn:=true must
        # turn required off (issue #33 item 4; docs/failsafe.md, "node killed").
        import roslaunch.config
        import roslaunch.xmlloader
        path = os.path.join(up.REPO, "launch", "bus.launch")
        for argv, respawn, required in (([], False, True), (["respawn:=true"], True, False)):
            config = roslaunch.config.ROSLaunchConfig()
            roslaunch.xmlloader.XmlLoader().load(path, config, argv=argv, verbose=False)
            node = next(n for n in config.nodes if n.type == "modbus_rtu_bus")
            self.assertEqual((node.respawn, node.required), (respawn, required), argv)
            self.assertEqual(node.respawn_delay, 1.0)

    def test_relaunch_keeps_nothing_of_the_previous_file(self):
        """bus.launch twice on one master: a fixed typo is not reported again, a removed
        share: is gone (its port closed), both on the parameter server and in the node."""
        log_dir = os.path.join(self.dir, "relaunch")
        os.makedirs(log_dir)
        link = os.path.join(log_dir, "tty")
        sim = up.start_simulator(os.path.join(up.REPO, "config", "simulator.yaml"), link, log_dir)
        base = {"port": "/dev/null", "baud": 9600,
                "devices": {"relays": {"type": "lc_relay8", "address": 8, "poll_rate": 5.0}}}

        def write(name, **changes):
            config = yaml.safe_load(yaml.safe_dump(base))
            for key, value in changes.items():
                if key == "relays":
                    config["devices"]["relays"].update(value)
                else:
                    config[key] = value
            path = os.path.join(log_dir, name + ".yaml")
            with open(path, "w") as f:
                yaml.safe_dump(config, f)
            return path
        try:
            # 1. A typo: the node stops naming it.
            typo = up.roslaunch(log_dir, "typo", "bus.launch",
                                "config:=" + write("typo", relays={"safe_stat": "off"}),
                                "port:=" + link)
            self.assertIsNotNone(typo.wait_exit(60), "the node did not stop on the typo")
            self.assertIn("safe_stat", typo.output())
            typo.stop()
            # 2. Fixed, with a share: the node runs and serves the share.
            port = up.free_port()
            shared = up.roslaunch(log_dir, "shared", "bus.launch",
                                  "config:=" + write("shared", relays={"safe_state": "off"},
                                                     share={"listen": "127.0.0.1:%d" % port}),
                                  "port:=" + link)
            try:
                up.check_device_answers("/modbus_bus", "relays", base["devices"]["relays"],
                                        log_dir, shared)
                self.assertTrue(connects(port), "the share did not listen")
            finally:
                shared.stop()
            # 3. The share removed from the file: gone from the parameter server and the node.
            plain = up.roslaunch(log_dir, "plain", "bus.launch", "config:=" + write("plain"),
                                 "port:=" + link)
            try:
                up.check_device_answers("/modbus_bus", "relays", base["devices"]["relays"],
                                        log_dir, plain)
                self.assertFalse(rospy.has_param("/modbus_bus/share"))
                self.assertFalse(rospy.has_param("/modbus_bus/devices/relays/safe_state"))
                self.assertFalse(connects(port), "the removed share still listens")
            finally:
                plain.stop()
        finally:
            sim.stop()


def connects(port):
    with socket.socket() as s:
        s.settimeout(2.0)
        return s.connect_ex(("127.0.0.1", port)) == 0


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "launch_files", LaunchFilesTest)
