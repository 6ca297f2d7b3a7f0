#!/usr/bin/env python3
"""A soak of the node under faults (issue 52): three devices polled at 50 Hz at 115200 (LC board
@8, LD58A08 @1, PDU @2), a SetBool caller in a loop, a Modbus TCP client on the share that checks
every answer's transaction id and its latency against the bound the node states in
/diagnostics, and a fault every `--period` s from the simulator's control socket, in a cycle:
10 % of the LC board's replies dropped; the LD58A08's next 20 replies corrupted; the PDU
silenced; the PDU back and 5 of the LC board's replies 200 ms late; a power cycle of every
board. At each fault, `--burst` more clients (default 4) each send one read at the same moment to
an address no device answers (every such request costs the link's timeout with every retry), so
that requests queue up behind each other: without the answer bound (docs/share.md) the last ones
are answered after a client has given up. Starts its own rosmaster, the simulator and the node
(free ports, a temporary folder).

Prints a table: RSS, fds and threads of the node over time; SetBool calls ok, refused and failed;
share answers by kind with p50/p99/max latency and the bound; answers later than the bound and
answers out of step; and per fault, the share answers and SetBool calls while it was the
latest one (to see where two builds differ). Exits 1 when an answer came late or out of step, the
node's RSS grew more than 0.5 MB after the first minute, or its threads or (by more than 2) its
fds grew.

    scripts/soak.sh --minutes N [--period S] [--timeout S] [--burst K] [--junit FILE] [--node EXE]
"""
import argparse
import contextlib
import logging
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray
from std_srvs.srv import SetBool

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "test"))
from sim_control import SimControl  # noqa: E402  (test/sim_control.py)
from mbap_client import MbapClient, ModbusError, read_pdu  # noqa: E402  (test/mbap_client.py)

RELAYS, PWM, PDU = "8", "1", "2"
ABSENT = 9  # an address with no device on the line
PHASES = ["before the first fault", "LC replies dropped", "LD58A08 replies corrupted",
          "PDU silent", "PDU back, LC replies late", "power cycle"]
FD_SLACK = 2  # fds a node may hold more for a while (roscpp's connections come and go)
SIM_YAML = """baud: 115200
parity: none
devices:
  - {type: lc_relay8, address: 8}
  - {type: ld58a08, address: 1}
  - {type: yespeed_pdu, address: 2}
"""
BUS_YAML = """baud: 115200
parity: none
diagnostic_period: 0.5
share: {listen: "127.0.0.1:%(share)d", max_clients: 8}
devices:
  relays: {type: lc_relay8, address: 8, poll_rate: 50}
  pwm_board: {type: ld58a08, address: 1, poll_rate: 50}
  pdu: {type: yespeed_pdu, address: 2, poll_rate: 50}
"""


def executable(name):
    return subprocess.check_output(["catkin_find", "--first-only", "--libexec",
                                    "modbus_rtu_driver", name], text=True).strip()


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def percentile(values, p):
    if not values:
        return float("nan")
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(p / 100.0 * (len(ordered) - 1))))]


@contextlib.contextmanager
def own_master():
    port = free_port()
    os.environ["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
    master = subprocess.Popen(["rosmaster", "--core", "-p", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 20
        while True:
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", port)) == 0:
                    break
            if time.monotonic() > deadline:
                raise RuntimeError("rosmaster did not start")
            time.sleep(0.1)
        rospy.init_node("modbus_rtu_soak", anonymous=True, disable_signals=True)
        logging.getLogger("rosout").setLevel(logging.ERROR)
        yield
    finally:
        master.terminate()
        master.wait(10)


class ShareClient(threading.Thread):
    """FC04 reads of the PDU's first 5 input registers through the share (mbpoll -t 3 -r 1
    -c 5), one at a time, as libmodbus does: wait up to the bound, then the next request. Every answer's transaction id is checked:
    one that answers an earlier request is out of step."""

    def __init__(self, port, bound, phase, unit=int(PDU), requests=None):
        super().__init__(daemon=True)
        self.port, self.bound, self.phase, self.unit = port, bound, phase, unit
        self.requests = requests  # None: until stopped
        self.kinds = {}  # "ok", "exception 0B", ... -> count
        self.latencies = []
        self.by_phase = {}  # phase -> [answers, sum of latencies]
        self.late = 0  # no answer within the bound
        self.out_of_step = 0
        self.stop = threading.Event()

    def run(self):
        with MbapClient(self.port, self.unit, timeout=10) as client:
            while not self.stop.is_set() and self.requests != 0:
                if self.requests:
                    self.requests -= 1
                sent = time.monotonic()
                transaction = client.send(read_pdu(0, 5, function=4))
                deadline = sent + self.bound
                while True:
                    try:
                        # The client gives up at the bound; a late answer is caught below.
                        got, _, answer = client.receive(max(0.0, deadline - time.monotonic()))
                    except ModbusError as e:
                        if e.closed:
                            raise RuntimeError("the share closed the connection") from None
                        self.late += 1
                        break
                    if got != transaction:
                        self.out_of_step += 1  # an earlier request's answer
                        continue
                    self.latencies.append(time.monotonic() - sent)
                    row = self.by_phase.setdefault(self.phase[0], [0, 0.0])
                    row[0] += 1
                    row[1] += self.latencies[-1]
                    kind = "ok" if answer[0] == 4 else "exception %02X" % answer[1]
                    self.kinds[kind] = self.kinds.get(kind, 0) + 1
                    break
                if self.requests is None:
                    time.sleep(0.02)


class SetBoolCaller(threading.Thread):
    def __init__(self, phase):
        super().__init__(daemon=True)
        self.phase = phase
        self.ok = self.refused = self.failed = 0
        self.reasons = {}
        self.by_phase = {}  # phase -> [ok, refused or failed]
        self.stop = threading.Event()

    def run(self):
        call = rospy.ServiceProxy("/soak_bus/relays/out0/set", SetBool)
        state = False
        while not self.stop.is_set():
            state = not state
            try:
                res = call(state)
                row = self.by_phase.setdefault(self.phase[0], [0, 0])
                row[0 if res.success else 1] += 1
                if res.success:
                    self.ok += 1
                else:
                    self.refused += 1
                    # "relays: out0 on: <why>": the why, without its variable details
                    reason = res.message.split(": ", 2)[-1].split(" (")[0][:70]
                    self.reasons[reason] = self.reasons.get(reason, 0) + 1
            except rospy.ServiceException:
                self.failed += 1
            time.sleep(0.05)


def process_figures(pid):
    with open("/proc/%d/status" % pid) as f:
        status = dict(line.split(":", 1) for line in f if ":" in line)
    rss = int(status["VmRSS"].split()[0]) / 1024.0
    threads = int(status["Threads"])
    fds = len(os.listdir("/proc/%d/fd" % pid))
    return rss, fds, threads


def share_value(key, timeout=30):
    """A value of the share's /diagnostics entry ("answer bound [s]", ...)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            msg = rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=2)
        except rospy.ROSException:
            continue
        for status in msg.status:
            if status.name.endswith("share"):
                for kv in status.values:
                    if kv.key == key:
                        return kv.value
    raise RuntimeError("no '%s' in the share's /diagnostics" % key)


def fault(sim, step):
    kind = step % 5
    if kind == 0:
        sim.drop(RELAYS, 10, "reply")
        return "10 %% of the LC board's replies dropped"
    if kind == 1:
        sim.drop(RELAYS, 0, "reply")
        sim.corrupt(PWM, 20)
        return "the LD58A08's next 20 replies corrupted"
    if kind == 2:
        sim.silence(PDU, True)
        return "the PDU silenced"
    if kind == 3:
        sim.silence(PDU, False)
        sim.spoil("late", RELAYS, 5, 200)
        return "the PDU back, 5 of the LC board's replies 200 ms late"
    sim.power_cycle()
    return "every board power-cycled"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=2.0)
    ap.add_argument("--period", type=float, default=20.0, help="s between faults")
    ap.add_argument("--burst", type=int, default=4,
                    help="clients that each read an absent address at once at each fault")
    ap.add_argument("--junit", help="also write the verdicts as JUnit cases to this file")
    ap.add_argument("--node", help="another build's modbus_rtu_bus (its libraries beside it), "
                    "to compare builds under the same simulator and faults")
    ap.add_argument("--timeout", type=float, default=0.0,
                    help="the client's timeout in s (default: the node's stated answer bound; "
                         "1.0 as mbpoll, for builds before the bound)")
    ap.add_argument("--wire-log", help="the node's wire_log (every frame, timed: for "
                    "bench/line_attribution.py or a comparison of two builds' lines)")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                    help="a bus parameter over the soak's configuration (rosparam syntax), "
                         "e.g. late_reply_guard=0 to measure what the guard costs")
    args = ap.parse_args()
    work = tempfile.mkdtemp(prefix="modbus_rtu_soak_")
    with open(os.path.join(work, "sim.yaml"), "w") as f:
        f.write(SIM_YAML)
    link, control = os.path.join(work, "tty"), os.path.join(work, "sim.ctl")
    share = free_port()
    with open(os.path.join(work, "bus.yaml"), "w") as f:
        f.write(BUS_YAML % {"share": share})
    with own_master():
        sim_proc = subprocess.Popen([executable("modbus_rtu_simulator"), "--config",
                                     os.path.join(work, "sim.yaml"), "--link", link,
                                     "--control", control, "--pace"],
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        while "simulator ready" not in sim_proc.stdout.readline():
            if sim_proc.poll() is not None:
                raise RuntimeError("the simulator did not start")
        threading.Thread(target=lambda: sim_proc.stdout.read(), daemon=True).start()
        subprocess.check_call(["rosparam", "load", os.path.join(work, "bus.yaml"), "/soak_bus"])
        subprocess.check_call(["rosparam", "set", "/soak_bus/port", link])
        for param in args.param:
            key, _, value = param.partition("=")
            subprocess.check_call(["rosparam", "set", "/soak_bus/" + key, value])
        if args.wire_log:
            subprocess.check_call(["rosparam", "set", "/soak_bus/wire_log",
                                   os.path.abspath(args.wire_log)])
        log = open(os.path.join(work, "node.log"), "w")
        node_env = dict(os.environ)
        if args.node:
            node_env["LD_LIBRARY_PATH"] = os.path.dirname(os.path.abspath(args.node))
        node = subprocess.Popen([args.node or executable("modbus_rtu_bus"), "__name:=soak_bus"],
                                stdout=log, stderr=subprocess.STDOUT, env=node_env)
        clients, bursts = [], []
        try:
            rospy.wait_for_service("/soak_bus/relays/out0/set", 30)
            bound = args.timeout or float(share_value("answer bound [s]"))
            phase = [0]  # PHASES' index of the latest fault, shared with the clients
            clients = [ShareClient(share, bound, phase), SetBoolCaller(phase)]
            bursts = []
            for c in clients:
                c.start()
            sim = SimControl(control)
            start = time.monotonic()
            end = start + 60.0 * args.minutes
            samples = [(0.0,) + process_figures(node.pid)]
            faults, step = [], 0
            # Samples fall between faults (5 s after a round 10), not when a burst's connections are open.
            next_fault, next_sample = start + args.period, start + 5.0
            while time.monotonic() < end and node.poll() is None:
                now = time.monotonic()
                if now >= next_fault:
                    faults.append(fault(sim, step))
                    phase[0] = 1 + step % 5
                    step += 1
                    for _ in range(args.burst):
                        bursts.append(ShareClient(share, bound, phase, ABSENT, requests=1))
                        bursts[-1].start()
                    next_fault += args.period
                if now >= next_sample:
                    samples.append((now - start,) + process_figures(node.pid))
                    next_sample += 10.0
                time.sleep(0.1)
            alive = node.poll() is None
            for c in clients:
                c.stop.set()
            expired = "-"
            if alive and not args.timeout:
                expired = share_value("answered 0B at the bound (unsent)")
        finally:
            for c in clients + bursts:
                c.stop.set()
            for c in clients + bursts:
                c.join(15)
            node.send_signal(2)
            try:
                node.wait(30)
            except subprocess.TimeoutExpired:
                node.kill()
            sim_proc.terminate()
            sim_proc.wait(10)
    client, caller = clients[0], clients[1]
    print("## soak: %.1f min, a fault every %.0f s (%d faults), answer bound %.3f s\n"
          % (args.minutes, args.period, len(faults), bound))
    print("| t [s] | RSS [MB] | fds | threads |\n|---|---|---|---|")
    for t, rss, fds, threads in samples:
        print("| %.0f | %.2f | %d | %d |" % (t, rss, fds, threads))
    print("\n| SetBool ok | refused | failed | refusals by reason |\n|---|---|---|---|")
    print("| %d | %d | %d | %s |" % (caller.ok, caller.refused, caller.failed,
                                     "; ".join("%s: %d" % kv for kv in sorted(caller.reasons.items()))))
    burst_late = sum(b.late for b in bursts)
    burst_oos = sum(b.out_of_step for b in bursts)
    burst_kinds = {}
    for b in bursts:
        for k, n in b.kinds.items():
            burst_kinds[k] = burst_kinds.get(k, 0) + n
    burst_lat = [x for b in bursts for x in b.latencies]
    lat = client.latencies
    print("\n| share answers | by kind | 0B at the bound | p50 [ms] | p99 [ms] | max [ms] | bound [ms] "
          "| late | out of step |")
    print("|---|---|---|---|---|---|---|---|---|")
    print("| %d | %s | %s | %.1f | %.1f | %.1f | %.0f | %d | %d |" % (
        len(lat), ", ".join("%s %d" % kv for kv in sorted(client.kinds.items())), expired,
        1e3 * percentile(lat, 50), 1e3 * percentile(lat, 99), 1e3 * max(lat or [float("nan")]),
        1e3 * bound, client.late, client.out_of_step))
    print("\n| burst reads of address %d (%d a fault) | by kind | max [ms] | late | out of step |"
          % (ABSENT, args.burst))
    print("|---|---|---|---|---|")
    print("| %d | %s | %.1f | %d | %d |" % (
        len(burst_lat), ", ".join("%s %d" % kv for kv in sorted(burst_kinds.items())),
        1e3 * max(burst_lat or [float("nan")]), burst_late, burst_oos))
    print("\n| latest fault | share answers | mean latency [ms] | SetBool ok | SetBool not ok |")
    print("|---|---|---|---|---|")
    for i, name in enumerate(PHASES):
        answers, total = client.by_phase.get(i, [0, 0.0])
        ok, not_ok = caller.by_phase.get(i, [0, 0])
        print("| %s | %d | %.1f | %d | %d |" % (name, answers, 1e3 * total / answers if answers
                                               else float("nan"), ok, not_ok))
    late, out_of_step = client.late + burst_late, client.out_of_step + burst_oos
    verdicts = {"the node runs to the end": "" if alive else
                "the node died (%s)" % os.path.join(work, "node.log")}
    verdicts["every share answer within the bound and in step"] = (
        "%d answers later than the client's timeout, %d out of step" % (late, out_of_step)
        if late or out_of_step else "")
    leaks = []
    after_minute = [s for s in samples if s[0] >= 60.0]
    if len(after_minute) >= 2:
        growth = after_minute[-1][1] - after_minute[0][1]
        if growth > 0.5:
            leaks.append("RSS grew %.2f MB after the first minute" % growth)
    # From 30 s on: the clients' connections and roscpp's threads are there by then. roscpp
    # opens and closes a connection now and then (one fd more for a while): a leak grows on.
    settled = [s for s in samples if s[0] >= 30.0]
    if len(settled) >= 2 and (settled[-1][2] > settled[0][2] + FD_SLACK or
                              settled[-1][3] > settled[0][3]):
        leaks.append("fds or threads grew (%d -> %d fds, %d -> %d threads)"
                     % (settled[0][2], settled[-1][2], settled[0][3], settled[-1][3]))
    verdicts["no growth of RSS, fds or threads"] = "; ".join(leaks)
    problems = [v for v in verdicts.values() if v]
    if args.junit:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from junit import write_suite  # noqa: E402  (scripts/junit.py)
        write_suite(args.junit, "soak", [(name, failure, None) for name, failure in
                                         verdicts.items()])
    print("\n" + ("soak: " + "; ".join(problems) if problems else "soak: passed"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
