"""The real parts of a scenario: the bus node (started and stopped here, as a robot's launch
would), the simulator (started and stopped here too: stopping it takes its pty away, as an
unplugged USB adapter), its control socket, the node's services, topics, share and diagnostics.
Every wait is for a condition, bounded by a deadline."""
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time

import rosparam
import rospy
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from std_msgs.msg import Bool, String

from modbus_rtu_driver.msg import DigitalStates, FailsafeEvent

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from sim_control import SimControl  # noqa: E402  (test/sim_control.py)

from model import LD_NAMES, NAMES  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "rostest"))
import helpers  # noqa: E402  (test/rostest/helpers.py)
from helpers import free_port  # noqa: E402
import user_paths  # noqa: E402  (test/rostest/user_paths.py: Process)

NODE = "scenbus"
NS = "/" + NODE + "/"
DEV = "relays"
BOARD = "1"
LD_DEV, LD_BOARD = "pwm", "2"   # the LD58A08 (bus.yaml, sim.yaml)
PDU_DEV, PDU_BOARD = "pdu", "3"  # the Yespeed PDU
DEVICES = (DEV, LD_DEV, PDU_DEV)


class Timeout(AssertionError):
    pass


# Every error a step raised, in order: when a failing example does not fail again on its replay
# (Hypothesis's Flaky), the first run's error is known only from here.
errors = []


def wait_until(predicate, timeout, what):
    # The rostests' wait, polled faster and raising Timeout, which the machine tells apart from
    # an invariant's AssertionError.
    try:
        return helpers.wait_until(predicate, timeout, what, interval=0.02, error=Timeout)
    except Timeout as e:
        errors.append("timeout: %s" % e)
        raise


class Harness:
    def __init__(self, sim_config, sim_control, port, log_dir, config_path):
        self.sim_args = ["rosrun", "modbus_rtu_driver", "modbus_rtu_simulator", "--config",
                         sim_config, "--link", port, "--control", sim_control]
        self.sim_control = sim_control
        self.port = port
        self.log_dir = log_dir
        os.makedirs(log_dir, exist_ok=True)  # scripts/scenarios.sh names a new one
        self.sim_process = None
        self.sim_starts = 0
        self.sim = None
        self.start_simulator()
        with open(config_path) as f:
            self.config = yaml.safe_load(f)
        self.config["port"] = port
        self.share_port = free_port()
        self.config["share"]["listen"] = "127.0.0.1:%d" % self.share_port
        self.node = None
        self.output = ""
        self.events = []
        self.polls = 0
        self.dev_polls = {d: 0 for d in DEVICES}  # outputs messages per device (one a poll)
        self.diag = None  # (time received, relays status)
        self.bus_diag = None  # (time received, the bus's status: "port not open: ...", ...)
        rospy.Subscriber(NS + "failsafe", FailsafeEvent, self.events.append, queue_size=100)
        # Each device's latched ~<device>/failsafe too: the node publishes its start events
        # before this test's subscription to a new node connects, and the latched ~failsafe
        # keeps only the newest of all devices (docs/failsafe.md). An event may come twice.
        for d in DEVICES:
            rospy.Subscriber(NS + d + "/failsafe", FailsafeEvent, self.events.append,
                             queue_size=100)
        rospy.Subscriber(NS + DEV + "/outputs", DigitalStates, self._on_outputs, queue_size=100)
        for d in (LD_DEV, PDU_DEV):
            rospy.Subscriber(NS + d + "/outputs", DigitalStates, self._on_dev_outputs, d,
                             queue_size=100)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self._on_diag, queue_size=100)
        self.commands = {n: rospy.Publisher(NS + DEV + "/" + n + "/command", Bool, queue_size=10)
                         for n in NAMES}
        self.ld_commands = {n: rospy.Publisher(NS + LD_DEV + "/" + n + "/command", Bool,
                                               queue_size=10) for n in LD_NAMES}
        self.alive = rospy.Publisher(self.config["heartbeat"]["topic"], String, queue_size=1)
        self.beats = 0
        self.beating = threading.Event()
        self.beating.set()
        threading.Thread(target=self._beat, daemon=True).start()

    def _beat(self):
        while not rospy.is_shutdown():
            if self.beating.is_set():
                self.alive.publish(String("alive"))
                self.beats += 1
            time.sleep(0.1)

    def _on_outputs(self, msg):
        self.polls += 1
        self.dev_polls[DEV] += 1

    def _on_dev_outputs(self, msg, dev):
        self.dev_polls[dev] += 1

    def _on_diag(self, msg):
        for s in msg.status:
            name = s.name.split(": ", 1)[-1]
            if name.endswith(DEV):
                self.diag = (msg.header.stamp.to_sec() or time.time(), s)
            elif name == "bus " + self.port:
                self.bus_diag = (msg.header.stamp.to_sec() or time.time(), s)

    # --- the simulator: its pty is the node's port -------------------------------------------
    def start_simulator(self):
        """A new simulator on the same link and control socket: a new board, every output off
        (no state file), as a board powered up again. Waits for its control socket (the old
        one is removed when a simulator stops, so this is the new one)."""
        if self.sim_process is not None and self.sim_process.running():
            return
        self.sim_starts += 1
        self.sim_process = user_paths.Simulator(self.sim_args, self.log_dir,
                                                "simulator%d" % self.sim_starts, self.port)
        wait_until(lambda: os.path.exists(self.sim_control) and os.path.exists(self.port)
                   or not self.sim_process.running(), 20, "the simulator's control socket")
        if not self.sim_process.running():
            raise AssertionError("the simulator did not start:\n" + self.sim_process.tail())
        self.sim = SimControl(self.sim_control)  # a client of the new simulator's socket
        wait_until(self._sim_answers, 10, "the simulator's control socket to answer")

    def _sim_answers(self):
        try:
            self.sim.info()
            return True
        except OSError:
            return False

    def stop_simulator(self):
        """The port goes away: the simulator stops at once (SIGTERM), its pty and link with it."""
        if self.sim_process is not None:
            self.sim_process.stop()
        self.sim = None

    def simulator_running(self):
        return self.sim_process is not None and self.sim_process.running()

    # --- the node ----------------------------------------------------------------------------
    def forget_kept_state(self):
        """A new robot: what earlier nodes kept on the parameter server for the next node (the
        timed commands still running, docs/failsafe.md) goes, as with a new
        roscore. Without this an example would resume the flashes of the example before it on
        a board that was power cycled and set anew, and its replay would not repeat it."""
        try:
            rospy.delete_param("/modbus_rtu_driver/running_timed/" + NODE)
        except KeyError:
            pass

    def start_node(self):
        rosparam.upload_params("/" + NODE, self.config)
        self.log = tempfile.TemporaryFile(mode="w+")
        self.node = subprocess.Popen(["rosrun", "modbus_rtu_driver", "modbus_rtu_bus",
                                      "__name:=" + NODE], stdout=self.log, stderr=subprocess.STDOUT)
        try:
            wait_until(lambda: self.node.poll() is not None or self._advertised(), 30,
                       "the node to advertise its services")
        except Timeout:
            pass
        if self.node.poll() is not None or not self._advertised():
            self.log.seek(0)
            errors.append("the node did not start (exit %s):\n%s"
                          % (self.node.poll(), self.log.read()[-3000:]))
            raise AssertionError(errors[-1])
        # The command topics are connected before a step publishes on them.
        for name, pub in list(self.commands.items()) + list(self.ld_commands.items()):
            wait_until(lambda: pub.get_num_connections() > 0, 15, name + "/command subscribed")

    def publishers_disconnected(self, timeout=2.0):
        """After a SIGKILL: the command topics' connections to the dead node are gone (bounded;
        a connection still counted then is left to the new node's subscription)."""
        pubs = list(self.commands.values()) + list(self.ld_commands.values())
        try:
            wait_until(lambda: all(p.get_num_connections() == 0 for p in pubs), timeout,
                       "the command topics' connections to the killed node to close")
        except Timeout:
            pass

    @staticmethod
    def _advertised():
        try:
            for service in (DEV + "/pump/set", LD_DEV + "/set_pwm", PDU_DEV + "/r0/set"):
                rospy.wait_for_service(NS + service, timeout=0.2)
            return True
        except rospy.ROSException:
            return False

    def node_tail(self, chars=4000):
        """The running node's output so far, its end (for a failure message)."""
        log = getattr(self, "log", None)
        if self.node is None or log is None:
            return getattr(self, "output", "")[-chars:]
        # pread: the node writes through the same open file, so its offset must not move.
        fd = log.fileno()
        size = os.fstat(fd).st_size
        start = max(0, size - chars)
        return os.pread(fd, size - start, start).decode(errors="replace")

    def stop_node(self, sig=signal.SIGINT, before=None):
        """Stops the node; returns its exit code. `before` runs just before the signal."""
        if self.node is None:
            return None
        if before:
            before()
        self.node.send_signal(sig)
        try:
            code = self.node.wait(30)
        except subprocess.TimeoutExpired:
            self.node.kill()
            code = self.node.wait(5)
        self.node = None
        self.log.seek(0)
        self.output = self.log.read()
        return code

    # --- the board and the node's answers ----------------------------------------------------
    def coils(self, board=BOARD):
        return self.sim.get(board, "coil", 0, 8)

    def enable(self, ch):
        """The LD58A08's enable register of channel `ch` (0x00n2), in the simulator."""
        return self.sim.get(LD_BOARD, "holding_register", ch * 16 + 2, 1)[0]

    def event(self, trigger, since, timeout, dev=DEV):
        return wait_until(lambda: next((e for e in self.events[since:]
                                        if e.trigger == trigger and e.device == dev), None),
                          timeout, "a %s event of %s on ~failsafe" % (trigger, dev))

    def wait_polls(self, n, timeout=5.0, dev=DEV):
        target = self.dev_polls[dev] + n
        wait_until(lambda: self.dev_polls[dev] >= target, timeout, "%d polls of %s" % (n, dev))

    def refused_unsent(self):
        """The device's "writes refused unsent (port not open)" count, in its newest status."""
        if not self.diag:
            return 0
        values = {v.key: v.value for v in self.diag[1].values}
        return int(values.get("writes refused unsent (port not open)", 0))

    def fresh_bus_status(self, predicate, timeout, what):
        """A /diagnostics status of the bus newer than now for which `predicate` holds."""
        since = time.time()
        return wait_until(lambda: self.bus_diag[1] if self.bus_diag and self.bus_diag[0] > since
                          and predicate(self.bus_diag[1]) else None, timeout, what)

    def fresh_diagnostics(self, timeout=5.0):
        since = time.time()
        return wait_until(lambda: self.diag[1] if self.diag and self.diag[0] > since else None,
                          timeout, "a new /diagnostics status of " + DEV)
