#!/usr/bin/env python3
"""Issue #32's fail-safe defects, each reproduced on the real node against the simulator, and
asserted in the simulator's coils (not the node's topics). Each test starts the node with its
own configuration and stops it. docs/failsafe.md is the spec: each test names the rule it
checks. On the code before the per-channel intents (91deab2) these tests fail, but for item 2,
which fails there only when the dead man's write comes before the next poll (a 5 s poll period
makes that likely, not certain; the deterministic simulation covers it exactly)."""
import copy
import os
import signal
import subprocess
import tempfile
import threading
import time
import unittest

import rosparam
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from std_msgs.msg import Bool, String
from std_srvs.srv import SetBool

from modbus_rtu_driver.msg import DigitalStates, FailsafeEvent, PwmStates
from modbus_rtu_driver.srv import Pulse, SetPwm

import helpers

NODE = "fsitems"
NS = "/" + NODE + "/"
# Where the node keeps its running timed commands for the next node (docs/ros_api.md).
KEPT = "/modbus_rtu_driver/running_timed/" + NODE + "/"
RELAYS, PWM, PDU = "8", "1", "2"
PUMP, VALVE, LAMP, FAN, OUT4, OUT5 = range(6)

BASE = {
    "baud": 9600, "parity": "none", "response_timeout": 0.3, "retries": 1,
    "diagnostic_period": 0.5, "shutdown_timeout": 3.0,
    "heartbeat": {"topic": "/robot/alive", "timeout": 1.0},
    "devices": {
        "relays": {
            "type": "lc_relay8", "address": 8, "poll_rate": 5.0,
            "outputs": ["pump", "valve", "lamp", "fan", "out4", "out5", "out6", "out7"],
            "safe_state": {"pump": False, "valve": False, "lamp": True},
            "command_timeout": {"valve": 1.0}, "on_restart": "restore"},
        "pwm_board": {"type": "ld58a08", "address": 1, "poll_rate": 5.0,
                      "safe_state": {"out0": False, "out1": True}, "on_restart": "restore"},
        "pdu": {"type": "yespeed_pdu", "address": 2, "poll_rate": 2.0},
    },
}


class FailsafeItemsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_failsafe_items")
        cls.sim = helpers.sim()
        cls.port = rospy.get_param("~port")
        cls.dir = rospy.get_param("~dir")
        cls.events = []
        rospy.Subscriber(NS + "failsafe", FailsafeEvent, cls.events.append)
        cls.alive = rospy.Publisher("/robot/alive", String, queue_size=1)
        cls.beating = threading.Event()
        cls.valve_on = threading.Event()
        cls.valve = rospy.Publisher(NS + "relays/valve/command", Bool, queue_size=1)
        threading.Thread(target=cls.publishers, daemon=True).start()
        cls.diag = helpers.Latest("/diagnostics", DiagnosticArray)
        cls.node = None
        cls.executable = subprocess.check_output(
            ["catkin_find", "--first-only", "--libexec", "modbus_rtu_driver", "modbus_rtu_bus"],
            text=True).strip()

    @classmethod
    def publishers(cls):
        while not rospy.is_shutdown():
            if cls.beating.is_set():
                cls.alive.publish(String("alive"))
            if cls.valve_on.is_set():
                cls.valve.publish(Bool(True))
            time.sleep(0.05)

    def setUp(self):
        for dev in (RELAYS, PWM, PDU):
            self.sim.silence(dev, False)
        self.sim.command("power_cycle")  # every output off; the node is not running
        self.beating.set()
        self.valve_on.clear()
        self.config = copy.deepcopy(BASE)
        self.config["port"] = self.port

    def tearDown(self):
        self.valve_on.clear()
        self.beating.set()
        for dev in (RELAYS, PWM, PDU):
            self.sim.silence(dev, False)
        self.stop_node()

    # --- the node ---
    def start_node(self, wait_service=True, fresh=True):
        """fresh: the previous test's keys are deleted first (a respawned node keeps them)."""
        if fresh and rospy.has_param("/" + NODE):
            rospy.delete_param("/" + NODE)  # the previous test's keys
        if fresh and rospy.has_param(KEPT):
            rospy.delete_param(KEPT)  # and the timed commands its node kept for the next one
        rosparam.upload_params("/" + NODE, self.config)
        self.log = tempfile.TemporaryFile(mode="w+")
        # The executable itself, not rosrun: a SIGINT that came while rosrun's shell was still
        # looking for it would be lost, and the node then holds the port through the next tests.
        type(self).node = subprocess.Popen([self.executable, "__name:=" + NODE],
                                           stdout=self.log, stderr=subprocess.STDOUT)
        if wait_service:
            helpers.service(NS + "relays/pump/set", SetBool, timeout=30)
            # Services come before the port (on a loaded machine, a node reopening a port the
            # previous one had just released is later still): the items' first calls need it.
            helpers.port_open(self.diag)

    def stop_node(self):
        if type(self).node is None:
            return
        node, type(self).node = type(self).node, None
        node.send_signal(signal.SIGINT)
        try:
            node.wait(30)
        except subprocess.TimeoutExpired:
            # Never left running: it would hold the port, and every later item would fail.
            node.kill()
            node.wait(10)
            self.fail("the node did not stop within 30 s of SIGINT (killed)")
        finally:
            self.log.seek(0)
            self.output = self.log.read()
            print(self.output)

    # --- what the simulator and the node show ---
    def coils(self, dev, n=8):
        return self.sim.get(dev, "coil", 0, n)

    def coil(self, dev, ch):
        return self.coils(dev)[ch]

    def wait_coils(self, dev, want, timeout, what):
        """want: {channel: level}; waits until the simulator's coils show all of them."""
        helpers.wait_until(lambda: all(self.coil(dev, c) == v for c, v in want.items()),
                           timeout, what + " (want %r)" % want)

    def hold_coils(self, dev, want, seconds, what):
        """The coils keep `want` for `seconds` (asserted every 0.1 s)."""
        end = time.time() + seconds
        while time.time() < end:
            got = self.coils(dev)
            self.assertEqual({c: got[c] for c in want}, want, what)
            time.sleep(0.1)

    def event(self, trigger, device, since, timeout=15):
        return helpers.wait_until(
            lambda: next((e for e in self.events[since:] if e.trigger == trigger and
                          e.device == device), None), timeout,
            "a %s event of %s" % (trigger, device))

    def set(self, name, state):
        res = helpers.service(NS + name + "/set", SetBool)(state)
        self.assertTrue(res.success, res.message)

    def diagnostics(self, device):
        return helpers.device_status(self.diag, device)

    def diagnostics_value(self, device, key):
        return helpers.device_value(self.diag, device, key)

    def pump_on_lamp_off_valve_by_topic(self):
        """Items 1 and 2 start here: pump on and lamp off by service, the valve on by its command
        topic (its dead man armed)."""
        self.set("relays/pump", True)
        self.set("relays/lamp", False)
        self.valve_on.set()
        self.wait_coils(RELAYS, {VALVE: 1}, 15, "valve on by its command topic")

    # --- the items ---
    def test_01_a_failed_dead_man_write_owes_only_its_channel(self):
        # docs/failsafe.md: "owes it on the channels it carried (not the others)".
        self.start_node()
        self.pump_on_lamp_off_valve_by_topic()
        since = len(self.events)
        self.sim.silence(RELAYS, True)
        self.valve_on.clear()
        e = self.event("command_timeout", "relays", since)
        self.assertFalse(e.confirmed, "written to a silent board?")
        self.sim.silence(RELAYS, False)
        self.wait_coils(RELAYS, {VALVE: 0}, 10, "the owed dead-man write")
        self.hold_coils(RELAYS, {PUMP: 1, LAMP: 0}, 2.0, "pump and lamp were not owed")

    def test_02_a_dead_man_write_does_not_pay_a_heartbeat_write(self):
        # docs/failsafe.md: "A later safe write that succeeds pays only its own channels."
        self.config["devices"]["relays"]["poll_rate"] = 0.2
        self.start_node()
        self.pump_on_lamp_off_valve_by_topic()
        since = len(self.events)
        self.sim.silence(RELAYS, True)
        self.beating.clear()
        e = self.event("heartbeat", "relays", since)
        self.assertFalse(e.confirmed, "written to a silent board?")
        self.sim.silence(RELAYS, False)
        # The valve's command (during the loss) ends its hold; its dead man then writes it off.
        self.valve_on.clear()
        self.wait_coils(RELAYS, {VALVE: 0}, 10, "the dead man's write")
        # The heartbeat is still lost: pump and lamp are owed and written (within two polls).
        self.wait_coils(RELAYS, {PUMP: 0, LAMP: 1}, 12, "the owed heartbeat safe states")

    def test_03_an_owed_safe_write_does_not_undo_a_newer_command(self):
        # docs/failsafe.md: owed writes are written "unless that channel was commanded after the
        # stamp".
        self.config["devices"]["relays"]["poll_rate"] = 0.2
        self.start_node()
        self.set("relays/pump", True)
        self.set("relays/lamp", False)
        since = len(self.events)
        self.sim.silence(RELAYS, True)
        self.beating.clear()
        self.assertFalse(self.event("heartbeat", "relays", since).confirmed)
        self.sim.silence(RELAYS, False)
        self.beating.set()
        self.set("relays/pump", True)  # confirmed by the board
        # The lamp's owed safe write comes at the next poll; the pump keeps the user's command.
        self.wait_coils(RELAYS, {LAMP: 1}, 12, "the lamp's owed safe state")
        self.hold_coils(RELAYS, {PUMP: 1}, 1.0, "the pump's newer command")

    def test_04a_a_flash_ends_at_its_final_level_after_an_outage(self):
        # docs/failsafe.md: restore writes "the final level of a timed command".
        self.start_node()
        self.set("relays/out4", True)
        res = helpers.service(NS + "relays/pulse", Pulse)(OUT4, True, 3.0)  # on 3 s, then off
        self.assertTrue(res.success, res.message)
        t0 = time.time()
        self.sim.silence(RELAYS, True)
        time.sleep(2.5)
        self.sim.silence(RELAYS, False)
        helpers.wait_until(lambda: time.time() > t0 + 3.0 + 0.56 + 1.0, 10, "the flash's end")
        self.hold_coils(RELAYS, {OUT4: 0}, 2.0, "out4 after the flash-close")

    def test_04b_a_burst_ends_off_and_a_restore_keeps_it_off(self):
        # docs/failsafe.md: an LD58A08 burst "is driven by the device until its end, then off".
        self.start_node()
        self.set("pwm_board/out0", True)
        self.set("pwm_board/out2", True)  # its drop shows the power cycle
        res = helpers.service(NS + "pwm_board/set_pwm", SetPwm)(0, 0.2, 0.1, 3, 0, 0, 0)
        self.assertTrue(res.success, res.message)
        time.sleep(1.5)  # three pulses of 0.2 s, and a poll after them
        since = len(self.events)
        self.sim.power_cycle(PWM)
        self.assertEqual(self.event("restart", "pwm_board", since).action, "restore")
        self.wait_coils(PWM, {2: 1}, 10, "out2 restored")
        self.hold_coils(PWM, {0: 0, 2: 1}, 2.0, "out0 after the burst and the restore")

    def test_05_a_share_clients_flash_is_a_command_not_a_restart(self):
        # docs/failsafe.md: a share client's FC16 that the type decodes (an LC flash) is a
        # command; its end is not a restart.
        port = helpers.free_port()
        self.config["share"] = {"listen": "127.0.0.1:%d" % port, "allow": ["127.0.0.1"]}
        self.start_node()
        restarts = self.diagnostics_value("relays", "restarts detected")
        since = len(self.events)
        flash_out5 = 3 + 5 * OUT5  # mode register, then tenths of a second
        self.assertEqual(
            helpers.modbus_tcp_write_registers(port, int(RELAYS), flash_out5, [4, 20]), "ok")
        self.wait_coils(RELAYS, {OUT5: 1}, 5, "the flash-close")
        self.wait_coils(RELAYS, {OUT5: 0}, 10, "the flash's end")
        time.sleep(2.0)  # polls after the end
        self.assertEqual(self.coil(RELAYS, OUT5), 0)
        self.assertFalse([e for e in self.events[since:] if e.trigger == "restart"],
                         "the flash's end was taken for a restart")
        self.assertEqual(self.diagnostics_value("relays", "restarts detected"), restarts)

    def test_06_a_killed_nodes_flash_is_not_a_restart_for_the_next_node(self):
        # docs/failsafe.md: the node keeps its running timed commands for its next start; a node
        # killed during a flash and started again does not take the flash's end for a restart.
        self.config["devices"]["relays"]["on_restart"] = "safe"
        self.start_node()
        self.set("relays/pump", True)
        res = helpers.service(NS + "relays/pulse", Pulse)(OUT4, True, 5.0)  # on 5 s, then off
        self.assertTrue(res.success, res.message)
        t0 = time.time()
        kept = helpers.wait_until(lambda: rospy.get_param(KEPT + "relays", None), 5,
                                  "the flash kept on the parameter server")
        self.assertEqual([(k["channel"], k["during"], k["after"]) for k in kept],
                         [(OUT4, 1, False)])
        type(self).node.kill()  # SIGKILL: no code of the node runs
        type(self).node.wait(10)
        type(self).node = None
        since = len(self.events)
        self.start_node(fresh=False)  # as roslaunch's respawn: the same roscore
        self.wait_coils(RELAYS, {OUT4: 0}, 15, "the flash's end")
        helpers.wait_until(lambda: time.time() > t0 + 5.0 + 0.6 + 1.5, 10, "polls after the end")
        self.assertFalse([e for e in self.events[since:] if e.device == "relays" and
                          e.trigger == "restart"], "the flash's end was taken for a restart")
        self.assertEqual(self.coil(RELAYS, PUMP), 1, "on_restart: safe switched the pump off")

    def test_06b_a_flash_a_clean_stop_ended_is_not_kept_for_the_next_node(self):
        # docs/failsafe.md: the node keeps its *running* timed commands for its next start. A
        # clean stop's safe write ends a flash on a channel with a safe state: the next node must
        # not resume it, take its safe level for a restart, nor write the channel.
        self.config["devices"]["relays"]["safe_state"]["out4"] = False
        FLASH = 12.0  # s: long enough for a stop and a start on a loaded machine
        self.start_node()
        res = helpers.service(NS + "relays/pulse", Pulse)(OUT4, True, FLASH)
        self.assertTrue(res.success, res.message)
        t0 = time.time()
        helpers.wait_until(lambda: rospy.get_param(KEPT + "relays", None), 5,
                           "the flash kept on the parameter server")
        self.stop_node()  # SIGINT: the shutdown's safe write switches out4 off
        self.assertEqual(self.coil(RELAYS, OUT4), 0, "the shutdown's safe write")
        kept = rospy.get_param(KEPT + "relays", [])
        self.assertFalse([k for k in kept if k["channel"] == OUT4],
                         "a flash the safe write ended is still kept: %r" % kept)
        since = len(self.events)
        self.start_node(fresh=False)  # as roslaunch's respawn: the same roscore
        self.assertLess(time.time(), t0 + FLASH, "the next node started after the flash's end")
        self.hold_coils(RELAYS, {OUT4: 0}, t0 + FLASH + 0.6 + 1.5 - time.time(),
                        "out4 written by the next node")  # through the flash's end and polls
        self.assertFalse([e for e in self.events[since:] if e.device == "relays" and
                          e.trigger == "restart"], "the safe write was taken for a restart")
        self.log.seek(0)
        self.assertNotIn("timed commands still run", self.log.read())

    def test_07_restore_writes_the_states_the_node_found(self):
        # docs/failsafe.md: "Where the node has commanded nothing, the intent is the state it
        # found at its first good poll".
        self.sim.set(RELAYS, "coil", FAN, 1)  # left on by the previous node
        outputs = helpers.Latest(NS + "relays/outputs", DigitalStates)
        self.start_node()
        outputs.wait(15, lambda m: m.states[FAN], "the first poll")
        since = len(self.events)
        self.sim.power_cycle(RELAYS)
        self.assertEqual(self.event("restart", "relays", since).action, "restore")
        self.wait_coils(RELAYS, {FAN: 1}, 10, "the fan restored")

    def test_07b_restore_starts_the_nodes_continuous_pwm_run_again(self):
        # docs/failsafe.md, "What restore writes": "a continuous PWM run the node started is
        # started again by a restore when the read just before the restore shows it stopped (a
        # power cycle without the power-down save)"; "Restart detection needs polls": such a run
        # read stopped is a restart. Before: the fan stayed off and /pwm showed it not running.
        pwm = helpers.Latest(NS + "pwm_board/pwm", PwmStates)
        self.start_node()
        res = helpers.service(NS + "pwm_board/set_pwm", SetPwm)(6, 0, 0, 0, 500, 40, 0)
        self.assertTrue(res.success, res.message)
        fan_regs = lambda: self.sim.get(PWM, "holding_register", 0x60, 3)  # noqa: E731
        self.assertEqual(fan_regs(), [500, 40, 0xFFFF])
        since = len(self.events)
        self.sim.power_cycle(PWM)  # power-down save off: every PWM register cleared
        self.assertEqual(fan_regs()[2], 0)
        # Only the run changed: the poll that reads channel 6's registers (one channel a poll,
        # 5 polls/s) sees it.
        event = self.event("restart", "pwm_board", since, timeout=20)
        self.assertEqual(event.action, "restore")
        helpers.wait_until(lambda: fan_regs() == [500, 40, 0xFFFF], 20,
                           "channel 6's continuous run started again, as set_pwm wrote it")
        self.assertTrue(any("PWM run started again on out6" in e.message
                            for e in self.events[since:]),
                        [e.message for e in self.events[since:]])
        pwm.wait(10, lambda m: m.channels[6].running and m.channels[6].continuous,
                 "/pwm: channel 6 running continuously again")

    def test_08_a_silent_board_at_start_does_not_lose_the_heartbeat(self):
        # docs/failsafe.md: the heartbeat is "armed when the node has written its on_start safe
        # states, just before it takes messages".
        self.config["response_timeout"] = 1.0
        self.config["retries"] = 2
        self.config["devices"]["relays"]["on_start"] = "safe"
        self.sim.set(PWM, "coil", 0, 1)
        self.sim.silence(RELAYS, True)
        since = len(self.events)
        self.start_node(wait_service=False)
        helpers.service(NS + "pwm_board/out0/set", SetBool, timeout=30)
        start = self.event("start", "relays", since, timeout=30)
        self.assertFalse(start.confirmed)
        time.sleep(2.0)
        self.assertFalse([e for e in self.events[since:] if e.trigger == "heartbeat"],
                         "the heartbeat was lost at start")
        self.assertEqual(self.coil(PWM, 0), 1, "out0 was switched off")

    def test_09_a_silent_board_goes_last_in_a_heartbeat_loss(self):
        # docs/failsafe.md: heartbeat lost: "safe states on every device ..., devices that
        # answered their last transaction first". The silent board is pwm_board, which comes
        # first in the node's order of devices (by name).
        self.config["response_timeout"] = 1.0
        self.config["retries"] = 2
        wire_log = os.path.join(self.dir, "items_wire.log")
        self.config["wire_log"] = wire_log
        self.start_node()
        self.set("pwm_board/out0", True)
        self.set("relays/pump", True)
        self.sim.silence(PWM, True)
        # The pwm board's poll fails (3 x 1 s): its last transaction failed, and it is not yet
        # offline (a write to an offline device is refused at once and costs nothing).
        helpers.wait_until(lambda: self.diagnostics_value("pwm_board", "consecutive failures")
                           in ("1", "2"), 15, "the pwm board's failed poll")
        before = len(helpers.wire_log(wire_log))
        self.beating.clear()
        self.wait_coils(RELAYS, {PUMP: 0, LAMP: 1}, 20, "the relays' safe states")
        time.sleep(0.5)  # the wire log is written by the publishing thread
        writes = [(f[3][0], f[3][1]) for f in helpers.wire_log(wire_log)[before:]
                  if f[0] == "tx" and f[3][1] in (5, 15)]
        self.assertTrue(writes, "no write in the wire log")
        self.assertEqual(writes[0][0], int(RELAYS),
                         "the silent board's safe write went first: %r" % writes)

    def test_11_diagnostics_show_the_heartbeat(self):
        # docs/failsafe.md: "While a heartbeat the device obeys is lost, its status is WARN
        # "heartbeat lost" ... once it is back, OK"; "A device with no safe state and
        # on_restart: leave only notes a restart (log INFO "restart detected")."
        self.start_node()
        since = len(self.events)
        self.beating.clear()
        self.event("heartbeat", "relays", since)
        self.event("heartbeat", "pwm_board", since)
        self.set("relays/fan", True)  # a write while the heartbeat is lost
        helpers.wait_until(lambda: self.diagnostics("relays").level == DiagnosticStatus.WARN and
                           "heartbeat lost" in self.diagnostics("relays").message, 10,
                           "relays WARN heartbeat lost after a write")
        self.beating.set()
        helpers.wait_until(lambda: self.diagnostics("pwm_board").level == DiagnosticStatus.OK, 10,
                           "pwm_board OK once the heartbeat is back")
        self.assertIn("out0", self.diagnostics_value("pwm_board", "held safe until commanded"))
        # Another master flips a PDU socket: a restart on a device with no fail-safe is a note.
        self.sim.set(PDU, "coil", 0, 1)
        helpers.wait_until(lambda: [e for e in self.events[since:] if e.device == "pdu"] or
                           self.diagnostics_value("pdu", "restarts detected") != "0", 10,
                           "the pdu's restart noted")
        self.stop_node()
        self.assertIn("pdu: restart detected", self.output)
        self.assertNotIn("pdu: fail-safe restart", self.output)


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "failsafe_items", FailsafeItemsTest)
