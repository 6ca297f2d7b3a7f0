"""What users run, run by the tests: roslaunch and the simulators started as the README and
docs/ show them, against the rostest's master (roslaunch finds it through ROS_MASTER_URI and
starts none of its own), and a device answer checked per device."""
import os
import signal
import socket
import subprocess
import tempfile
import time

import rospkg
import rospy
import yaml

from helpers import wait_until

REPO = rospkg.RosPack().get_path("modbus_rtu_driver")


def free_port():
    """A TCP port nobody listens on now (bound with port 0, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Process:
    """A command in its own process group, its output kept in a file for failure messages."""

    def __init__(self, args, log_dir, name, env=None, cwd=None, stdin=None):
        self.args = args
        self.log_path = os.path.join(log_dir, name + ".log")
        self.log = open(self.log_path, "w")
        self.proc = subprocess.Popen(args, stdout=self.log, stderr=subprocess.STDOUT,
                                     stdin=subprocess.PIPE if stdin is not None else None,
                                     start_new_session=True, env=env, cwd=cwd)
        if stdin is not None:  # what a user types at a prompt
            self.proc.stdin.write(stdin.encode())
            self.proc.stdin.close()

    def output(self):
        if not self.log.closed:
            self.log.flush()
        with open(self.log_path, errors="replace") as f:
            return f.read()

    def running(self):
        return self.proc.poll() is None

    def wait_exit(self, timeout):
        try:
            return self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            return None

    def stop(self, timeout=20, sig=signal.SIGINT):
        """`sig` to the group (SIGINT: as Ctrl-C), SIGKILL if it is still there after `timeout`
        s."""
        if self.running():
            os.killpg(self.proc.pid, sig)
            if self.wait_exit(timeout) is None:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        self.log.close()
        return self.proc.returncode

    def tail(self, lines=40):
        return "\n".join(self.output().splitlines()[-lines:])


class Simulator(Process):
    """modbus_rtu_simulator on `link`. stop() is the USB adapter pulled: SIGTERM, which stops it
    at once and removes its link (docs/simulator.md). Not SIGINT: that waits up to 20 s for the
    node to let go of the port, and a kill after the same 20 s left the link behind, pointing at
    a pty number that the next pty made (another test's simulator) gets; the node, reopening its
    port, opened that pty and took its lock (issue 49's load failures)."""

    def __init__(self, args, log_dir, name, link):
        super().__init__(args, log_dir, name)
        self.link = link

    def stop(self, timeout=20, sig=signal.SIGTERM):
        code = super().stop(timeout, sig)
        if os.path.lexists(self.link):
            raise AssertionError("the simulator on %s stopped (exit %s) and left its link behind:"
                                 " a program reopening it may open another pty\n%s"
                                 % (self.link, code, self.tail()))
        return code


def wait_for_file(path, timeout, what, process=None):
    def there():
        if process is not None and not process.running():
            raise AssertionError("%s exited (%s) before %s appeared:\n%s"
                                 % (process.args, process.proc.returncode, path, process.tail()))
        return os.path.exists(path)
    wait_until(there, timeout, what)


def start_simulator(config, link, log_dir, name="simulator"):
    """modbus_rtu_simulator as docs/simulator.md starts it; waits for its link."""
    sim = Simulator(["rosrun", "modbus_rtu_driver", "modbus_rtu_simulator", "--config", config,
                     "--link", link], log_dir, name, link)
    wait_for_file(link + ".ctl", 20, "the simulator's control socket " + link + ".ctl", sim)
    return sim


def roslaunch(log_dir, name, *args):
    """`roslaunch modbus_rtu_driver ARGS...`, exactly as typed in a shell."""
    return Process(["roslaunch", "modbus_rtu_driver"] + list(args), log_dir, name)


def bus_devices(config_path):
    with open(config_path) as f:
        config = yaml.safe_load(f)
    devices = config.get("devices", {})
    return config, devices if isinstance(devices, dict) else {}


def simulator_config_for(config_path, out_dir):
    """A simulator configuration with the bus configuration's devices: an example in config/
    that simulates exactly those devices when there is one, else one written from the bus's
    device list (generic devices keep their signals, template and max_gap)."""
    config, devices = bus_devices(config_path)
    wanted = sorted((d["type"], int(d["address"])) for d in devices.values())
    for candidate in sorted(os.listdir(os.path.join(REPO, "config"))):
        if not candidate.startswith("simulator"):
            continue
        path = os.path.join(REPO, "config", candidate)
        with open(path) as f:
            sim = yaml.safe_load(f)
        have = sorted((d["type"], int(d["address"])) for d in sim.get("devices", []))
        if have == wanted and sim.get("baud", 9600) == config.get("baud", 9600):
            return path
    config_dir = os.path.dirname(config_path)
    sim_devices = []
    for d in devices.values():
        item = {"type": d["type"], "address": int(d["address"])}
        for key in ("signals", "max_gap"):
            if key in d:
                item[key] = d[key]
        if "template" in d:
            item["template"] = os.path.join(config_dir, d["template"])
        sim_devices.append(item)
    path = os.path.join(out_dir, "sim_" + os.path.basename(config_path))
    with open(path, "w") as f:
        yaml.safe_dump({"baud": config.get("baud", 9600), "parity": config.get("parity", "none"),
                        "devices": sim_devices}, f)
    return path


def signals_of(device, config_dir):
    """A generic device's signals: the template's, then its own (as the node adds them)."""
    signals = []
    if "template" in device:
        with open(os.path.join(config_dir, device["template"])) as f:
            signals += yaml.safe_load(f)["signals"]
    return signals + device.get("signals", [])


def check_device_answers(namespace, name, device, config_dir, launch):
    """One state topic seen and one service answered with success for a bus device."""
    from std_srvs.srv import SetBool
    from modbus_rtu_driver.msg import DigitalStates, SignalValues
    from modbus_rtu_driver.srv import SetValue

    base = "%s/%s" % (namespace, name)

    def alive():
        if not launch.running():
            raise AssertionError("roslaunch exited (%s):\n%s"
                                 % (launch.proc.returncode, launch.tail()))
    if device["type"] == "generic":
        msg = wait_for_message(base + "/signals", SignalValues,
                               lambda m: any(m.valid), alive)
        writable = [s for s in signals_of(device, config_dir) if s.get("writable")]
        if not writable:
            return "%s/signals: %s" % (base, ", ".join(msg.names))
        s = writable[0]
        service = "%s/%s/set" % (base, s["name"])
        if s.get("table") == "coil" or s.get("type") == "bool":
            res = call(service, SetBool, alive, False)
        else:
            value = min(max(0.0, float(s.get("min", 0.0))), float(s.get("max", 0.0)))
            res = call(service, SetValue, alive, value)
    else:
        msg = wait_for_message(base + "/outputs", DigitalStates, lambda m: not m.stale, alive)
        service = "%s/%s/set" % (base, msg.names[0])
        res = call(service, SetBool, alive, False)
    if not res.success:
        raise AssertionError("%s answered success false: %s" % (service, res.message))
    return "%s: %s" % (service, res.message)


def wait_for_message(topic, msg_type, predicate, alive, timeout=30):
    got = []
    sub = rospy.Subscriber(topic, msg_type, lambda m: got.append(m) if predicate(m) else None)
    try:
        def seen():
            alive()
            return got[-1] if got else None
        return wait_until(seen, timeout, "a message on " + topic)
    finally:
        sub.unregister()


def call(service, srv_type, alive, *args, timeout=30):
    deadline = time.time() + timeout
    while True:
        alive()
        try:
            rospy.wait_for_service(service, timeout=1.0)
            break
        except rospy.ROSException:
            if time.time() > deadline:
                raise AssertionError("service %s never appeared" % service)
    return rospy.ServiceProxy(service, srv_type)(*args)


def scratch_dir(prefix):
    return tempfile.mkdtemp(prefix=prefix)


def assert_shutdown_safe_writes_confirmed(test, output, devices):
    """The node's stop wrote and confirmed each device's safe states (docs/failsafe.md: stderr
    `D: fail-safe shutdown (node stops): ...`, `NOT confirmed` when not)."""
    for device in devices:
        test.assertRegex(output, r"\[WARN\] %s: fail-safe shutdown \(node stops\)" % device, output)
    test.assertNotIn("NOT confirmed", output, output)
    test.assertNotIn("safe states not", output, output)
