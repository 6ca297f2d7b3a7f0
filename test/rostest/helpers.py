"""Shared pieces of the rostests: the simulator's control socket and waiting helpers."""
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

import rosparam
import rospkg
import rospy
import yaml
from std_msgs.msg import String

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from sim_control import SimControl  # noqa: E402  (test/sim_control.py)
from mbap_client import write_coil_pdu, write_outcome, write_registers_pdu  # noqa: E402


def sim():
    """The simulator of this test, at the control socket named by ~sim_control."""
    path = rospy.get_param("~sim_control")
    deadline = time.time() + 20
    while not os.path.exists(path):
        if time.time() > deadline:
            raise RuntimeError("simulator control socket %s never appeared" % path)
        time.sleep(0.1)
    return SimControl(path)


def free_port():
    """A TCP port free on 127.0.0.1 now, for a server the test starts (and may start again).
    Chosen below the kernel's ephemeral range: a port the kernel gives for port 0 comes from that
    range, where any outgoing connection (ROS opens many) may take it as its local port before
    the server binds it ("address in use": the scenario test's seed 126919435 in stop 39)."""
    low = 32768
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as f:
            low = int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        pass
    chooser = random.SystemRandom()
    for _ in range(200):
        port = chooser.randrange(max(1024, low - 16384), low)
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:  # the kernel's choice, then
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(predicate, timeout, what, interval=0.05, error=AssertionError):
    """Polls predicate() every `interval` s until it is true; raises `error` naming `what`
    otherwise (an AssertionError fails the calling test)."""
    deadline = time.time() + timeout
    last = None
    while time.time() < deadline and not rospy.is_shutdown():
        last = predicate()
        if last:
            return last
        time.sleep(interval)
    raise error("timed out after %.1f s waiting for %s (last: %r)" % (timeout, what, last))


class Latest:
    """Keeps the newest message of a topic, and how many arrived."""

    def __init__(self, topic, msg_type):
        self.msg = None
        self.count = 0
        self.sub = rospy.Subscriber(topic, msg_type, self._cb)

    def _cb(self, msg):
        self.msg = msg
        self.count += 1

    def wait(self, timeout=10.0, predicate=lambda m: True, what="a message"):
        return wait_until(lambda: self.msg if self.msg is not None and predicate(self.msg) else None,
                          timeout, what + " on " + self.sub.name)


def bus_config(filename):
    """The bus configuration test/rostest/<filename>, on the port of this test's line (~port)."""
    path = os.path.join(rospkg.RosPack().get_path("modbus_rtu_driver"), "test", "rostest",
                        filename)
    with open(path) as f:
        config = yaml.safe_load(f)
    config["port"] = rospy.get_param("~port")
    return config


def heartbeat(topics, interval=0.05):
    """Publishes "alive" on each of `topics` every `interval` s from a daemon thread while the
    returned Event is set (set at the start; clear it to lose the heartbeat)."""
    publishers = [rospy.Publisher(topic, String, queue_size=1) for topic in topics]
    beating = threading.Event()
    beating.set()

    def beat():
        while not rospy.is_shutdown():
            if beating.is_set():
                for pub in publishers:
                    pub.publish(String("alive"))
            time.sleep(interval)

    threading.Thread(target=beat, daemon=True).start()
    return beating


class BusNode:
    """The bus node run by the test itself, to start it on outputs left set and to stop it with
    a signal; `output` is what it printed, kept after the stop for the test to read."""

    def __init__(self, name):
        self.name = name
        self.process = None
        self.output = ""
        self._log = None

    @property
    def running(self):
        return self.process is not None

    def start(self, config, fresh=False):
        """Uploads `config` as the node's parameters (fresh: the previous ones deleted first, so
        no key of an earlier start stays) and starts the node."""
        if fresh and rospy.has_param("/" + self.name):
            rosparam.delete_param("/" + self.name)
        rosparam.upload_params("/" + self.name, config)
        self._log = tempfile.TemporaryFile(mode="w+")
        self.process = subprocess.Popen(["rosrun", "modbus_rtu_driver", "modbus_rtu_bus",
                                         "__name:=" + self.name],
                                        stdout=self._log, stderr=subprocess.STDOUT)

    def stop(self, sig=signal.SIGINT):
        """Sends `sig` and waits (30 s at most) for the exit: its code, None when not running."""
        if self.process is None:
            return None
        self.process.send_signal(sig)
        code = self.process.wait(30)
        self.process = None
        self._log.seek(0)
        self.output = self._log.read()
        print(self.output)
        return code


def service(name, srv_type, timeout=20.0):
    rospy.wait_for_service(name, timeout=timeout)
    return rospy.ServiceProxy(name, srv_type)


def wire_log(path):
    """The node's wire_log (docs/ros_api.md): (direction, first, last, frame bytes, cpu, waits)
    per whole line, where waits is (late, guard) for a request and None for a reply."""
    if not os.path.exists(path):
        return []
    out = []
    with open(path) as f:
        for line in f:
            if not line.endswith("\n"):
                break  # being written
            direction, first, last, rest = line.rstrip("\n").split(" ", 3)
            hexed, cpu = rest.split(" cpu=")
            waits = None
            if direction == "tx":
                cpu, late = cpu.split(" late=")
                waits = tuple(float(w) for w in late.split(" guard="))
            out.append((direction, float(first), float(last), bytes.fromhex(hexed), float(cpu),
                        waits))
    return out


def device_status(diagnostics, device):
    """The /diagnostics status of `device` in a message published after this call (diagnostics:
    a Latest of /diagnostics)."""
    diagnostics.msg = None
    return wait_until(
        lambda: next((s for s in (diagnostics.msg.status if diagnostics.msg else [])
                      if s.name.endswith("device " + device)), None), 10,
        "diagnostics of " + device)


def bus_status(diagnostics, predicate, timeout, what):
    """The /diagnostics status of the bus (named "bus PORT") in a message published after this
    call for which predicate(status) holds (diagnostics: a Latest of /diagnostics)."""
    diagnostics.msg = None
    return wait_until(
        lambda: next((s for s in (diagnostics.msg.status if diagnostics.msg else [])
                      if s.name.split(": ", 1)[-1].startswith("bus ") and predicate(s)), None),
        timeout, what)


def port_open(diagnostics, timeout=30):
    """Waits for the bus's port to be open: a node's services come before its port, and a
    request before then is refused ("port not open")."""
    return bus_status(diagnostics, lambda s: not s.message.startswith("port not open"), timeout,
                      "the bus's port open (its status in /diagnostics)")


def device_value(diagnostics, device, key):
    """One key's value in device_status."""
    return next(kv.value for kv in device_status(diagnostics, device).values if kv.key == key)


def modbus_tcp_write_coil(port, unit, coil, state):
    """FC05 through a Modbus TCP server (the share): "ok" when the whole request is echoed,
    "exception N" on an exception (mbap_client.write_outcome)."""
    return write_outcome(port, unit, write_coil_pdu(coil, state), 5)


def modbus_tcp_write_registers(port, unit, address, values):
    """FC16: "ok" when the answer echoes the address and the count."""
    return write_outcome(port, unit, write_registers_pdu(address, values), 5)
