#!/usr/bin/env python3
"""The node's share of the benchmark (a script, not a test): service-to-wire and
service-to-answer latency of SetBool while the node polls three devices, and the node's CPU use
while polling three devices at 50 Hz each. Starts its own rosmaster, the simulator and the node
from the sourced catkin workspace; prints markdown tables; appends CSV rows to --csv.

    node_bench.py [--calls N] [--bauds 115200,9600] [--cpu-seconds S (0: skip)] [--csv FILE]
                  [--repeats R] [--hog N] [--realtime P]

Each figure is measured --repeats times (5 by default) and shown as the median with the spread
(lowest-highest) of the runs, so the machine's noise is in the table. With --hog N, N busy
processes keep the CPUs loaded and the 115200 latency is measured again with the bus thread at
normal priority and at SCHED_FIFO --realtime P (the node's realtime_priority).
"""
import argparse
import contextlib
import json
import logging
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray
from std_srvs.srv import SetBool

SIM_YAML = """baud: %(baud)d
parity: none
devices:
  - {type: lc_relay8, address: 8}
  - {type: ld58a08, address: 1}
  - {type: yespeed_pdu, address: 2}
"""

BUS_YAML = """baud: %(baud)d
parity: none
diagnostic_period: 0.5
devices:
  relays: {type: lc_relay8, address: 8, poll_rate: %(rate)s}
  pwm_board: {type: ld58a08, address: 1, poll_rate: %(rate)s}
  pdu: {type: yespeed_pdu, address: 2, poll_rate: %(rate)s}
"""


def executable(name):
    return subprocess.check_output(["catkin_find", "--first-only", "--libexec",
                                    "modbus_rtu_driver", name], text=True).strip()


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Simulator:
    """The simulator with --verbose --timestamps; keeps every frame with its times."""

    def __init__(self, workdir, pace, baud=115200):
        config = os.path.join(workdir, "sim.yaml")
        with open(config, "w") as f:
            f.write(SIM_YAML % {"baud": baud})
        self.link = os.path.join(workdir, "tty")
        args = [executable("modbus_rtu_simulator"), "--config", config, "--link", self.link,
                "--verbose", "--timestamps"] + (["--pace"] if pace else [])
        self.proc = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
        self.rx = []  # (first byte, hex) of every request
        self.frames = []  # (rx or tx, first byte, last byte, hex) in line order
        while "simulator ready" not in self.proc.stdout.readline():
            pass
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        # "rx FIRST LAST HEX": when the request's first and last byte reached the simulator;
        # "tx FIRST LAST HEX": when the reply's first and last byte were written.
        for line in self.proc.stdout:
            parts = line.split(" ", 3)
            if len(parts) == 4 and parts[0] in ("rx", "tx"):
                self.frames.append((parts[0], float(parts[1]), float(parts[2]),
                                    parts[3].strip()))
                if parts[0] == "rx":
                    self.rx.append((float(parts[1]), parts[3].strip()))

    def stop(self):
        self.proc.terminate()
        self.proc.wait(10)


class Node:
    def __init__(self, workdir, port, rate, baud=115200, extra_yaml="", prefix=(), exe=None,
                 env=None, only=None):
        """prefix: a command the node runs under (valgrind); exe: another build's node; only: the
        one device of BUS_YAML to configure (relays, pwm_board, pdu), the others left out."""
        config = os.path.join(workdir, "bus.yaml")
        with open(config, "w") as f:
            text = BUS_YAML % {"rate": rate, "baud": baud}
            if only:
                text = "\n".join(l for l in text.splitlines()
                                 if not l.startswith("  ") or l.startswith("  %s:" % only)) + "\n"
            f.write(text + extra_yaml)
        subprocess.check_call(["rosparam", "delete", "/bench_bus"], stderr=subprocess.DEVNULL) \
            if self._has_params() else None
        subprocess.check_call(["rosparam", "load", config, "/bench_bus"])
        subprocess.check_call(["rosparam", "set", "/bench_bus/port", port])
        self.log = os.path.join(workdir, "node.log")
        with open(self.log, "w") as log:
            self.proc = subprocess.Popen(list(prefix) + [exe or executable("modbus_rtu_bus"),
                                                         "__name:=bench_bus"],
                                         stdout=log, stderr=subprocess.STDOUT, env=env)

    def wait_ready(self, timeout=30, service="relays/out0/set"):
        try:
            rospy.wait_for_service("/bench_bus/" + service, timeout)
        except rospy.ROSException:
            with open(self.log) as f:
                sys.stderr.write(f.read())
            raise

    @staticmethod
    def _has_params():
        return subprocess.call(["rosparam", "get", "/bench_bus"], stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL) == 0

    def cpu_seconds(self):
        with open("/proc/%d/stat" % self.proc.pid) as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def thread_cpu_seconds(self):
        """CPU seconds by thread name: the bus thread is 'modbus_bus', the rest are roscpp's
        (publishing, the service spinner, timers, diagnostics)."""
        by_name = {}
        for tid in os.listdir("/proc/%d/task" % self.proc.pid):
            try:
                with open("/proc/%d/task/%s/stat" % (self.proc.pid, tid)) as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue  # the thread ended
            name = "bus thread" if self._comm(tid) == "modbus_bus" else "ROS threads"
            seconds = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
            by_name[name] = by_name.get(name, 0.0) + seconds
        return by_name

    def bus_thread_wakeups(self):
        """The bus thread's voluntary context switches so far: each is a sleep and a wake-up."""
        for tid in os.listdir("/proc/%d/task" % self.proc.pid):
            if self._comm(tid) == "modbus_bus":
                with open("/proc/%d/task/%s/status" % (self.proc.pid, tid)) as f:
                    for line in f:
                        if line.startswith("voluntary_ctxt_switches:"):
                            return int(line.split()[1])
        return 0

    def _comm(self, tid):
        with open("/proc/%d/task/%s/comm" % (self.proc.pid, tid)) as f:
            return f.read().strip()

    def stop(self):
        self.proc.terminate()
        self.proc.wait(20)


@contextlib.contextmanager
def own_master(node_name):
    """A rosmaster of the benchmark's own on a free port, and this process as node_name on it,
    so a benchmark never meets a running robot's graph."""
    port = free_port()
    os.environ["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
    master = subprocess.Popen(["rosmaster", "--core", "-p", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(1.5)
        rospy.init_node(node_name, anonymous=True, disable_signals=True)
        logging.getLogger("rosout").setLevel(logging.ERROR)  # keep the tables clean
        yield
    finally:
        master.terminate()
        master.wait(10)


def percentile(values, p):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(p / 100.0 * (len(ordered) - 1))))]


class Hog:
    """N busy processes at normal priority: a loaded robot computer."""

    def __init__(self, n):
        self.procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                      for _ in range(n)]

    def stop(self):
        for p in self.procs:
            p.kill()
            p.wait()


def spread(values, fmt="%.2f"):
    """'median (lowest-highest)' of one figure over the repeats."""
    if not values:
        return "-"
    if len(values) == 1:
        return fmt % values[0]
    return (fmt + " (" + fmt + "-" + fmt + ")") % (statistics.median(values), min(values),
                                                 max(values))


def raise_simulator(sim):
    """Under load the simulator must keep its pace, or its delays would count as the node's:
    SCHED_FIFO 60 for each of its threads where allowed. True when granted."""
    try:
        for tid in os.listdir("/proc/%d/task" % sim.proc.pid):
            os.sched_setscheduler(int(tid), os.SCHED_FIFO, os.sched_param(60))
        return True
    except OSError:
        return False


def measure_latency(workdir, calls, baud, realtime=0, loaded=False):
    """One run: (to-the-wire seconds, to-the-answer seconds, failed calls, simulator raised)."""
    sim = Simulator(workdir, pace=True, baud=baud)
    sim_raised = raise_simulator(sim) if loaded else False
    node = Node(workdir, sim.link, 10.0, baud, "realtime_priority: %d\n" % realtime)
    try:
        node.wait_ready()
        pump = rospy.ServiceProxy("/bench_bus/relays/out0/set", SetBool, persistent=True)
        time.sleep(2.0)  # polling under way
        wire, answer, failed = [], [], 0
        for i in range(calls):
            want = i % 2 == 0
            frame = "08 05 00 00 %s" % ("FF 00" if want else "00 00")
            seen = len(sim.rx)
            t0 = time.monotonic()
            res = pump(want)
            t1 = time.monotonic()
            if not res.success:
                failed += 1
                continue
            answer.append(t1 - t0)
            time.sleep(0.005)  # the simulator's line reader prints the frame
            for t, hexed in sim.rx[seen:]:
                if hexed.startswith(frame) and t >= t0:
                    wire.append(t - t0)
                    break
            time.sleep(0.01 + (i % 7) * 0.003)  # land at different points of the poll cycle
    finally:
        node.stop()
        sim.stop()
    return wire, answer, failed, sim_raised


def transaction_time(baud):
    # One transaction's wire time at the baud, 8N1: the longest poll, FC04 5 registers (8 + 15
    # bytes) with t3.5 after the request and after the reply (1.75 ms above 19200 baud).
    t35 = 3.5 * 11 / baud if baud <= 19200 else 0.00175
    return (8 + 15) * 10.0 / baud + 2 * t35


def figures(runs):
    """Per run (p50, p99, max) in ms of each list of seconds."""
    return [(1e3 * percentile(v, 50), 1e3 * percentile(v, 99), 1e3 * max(v)) for v in runs if v]


def latency(workdir, calls, csv, baud, repeats):
    transaction = transaction_time(baud)
    target = 0.002 + transaction
    runs = [measure_latency(workdir, calls, baud) for _ in range(repeats)]
    print("## Latency of SetBool while polling 3 devices at 10 Hz (paced %d line, %d calls, "
          "%d runs)\n" % (baud, calls, repeats))
    print("| from the call to | p50 [ms] | p99 [ms] | max [ms] | target p99 [ms] |")
    print("|---|---|---|---|---|")
    for index, name in ((0, "the frame on the line"), (1, "the answer")):
        f = figures([run[index] for run in runs])
        print("| %s | %s | %s | %s | %s |" % (
            name, spread([x[0] for x in f]), spread([x[1] for x in f]), spread([x[2] for x in f]),
            "%.2f (2 ms + one transaction, %.2f ms)" % (1e3 * target, 1e3 * transaction)
            if index == 0 else ""))
        if f:
            csv.write("latency_%d,%s,%f,%f,%f\n" % (
                baud, name.replace(" ", "_"), statistics.median(x[0] for x in f) / 1e3,
                statistics.median(x[1] for x in f) / 1e3, target))
    matched = sum(len(run[0]) for run in runs)
    failed = sum(run[2] for run in runs)
    print("\nMedian (lowest-highest) over the runs. %d of %d calls matched to their frame; %d "
          "failed.\n" % (matched, calls * repeats, failed))


def tail_latency(workdir, calls, csv, hogs, priority, repeats):
    """SetBool to the wire at 115200 with the CPUs loaded, normal priority against SCHED_FIFO."""
    hog = Hog(hogs)
    try:
        rows = []
        for label, rt in (("normal", 0), ("SCHED_FIFO %d" % priority, priority)):
            runs = [measure_latency(workdir, calls, 115200, rt, True) for _ in range(repeats)]
            rows.append((label, figures([run[0] for run in runs])))
            sim_raised = all(run[3] for run in runs)
    finally:
        hog.stop()
    print("## SetBool to the wire under load (%d busy processes on %d CPUs, paced 115200 line, "
          "%d calls, %d runs)\n" % (hogs, os.cpu_count(), calls, repeats))
    print("| bus thread | p50 [ms] | p99 [ms] | max [ms] |")
    print("|---|---|---|---|")
    for label, f in rows:
        print("| %s | %s | %s | %s |" % (label, spread([x[0] for x in f]),
                                         spread([x[1] for x in f]), spread([x[2] for x in f])))
        if f:
            csv.write("tail_latency,%s,%f,%f,%f\n" % (
                label.replace(" ", "_"), statistics.median(x[0] for x in f) / 1e3,
                statistics.median(x[1] for x in f) / 1e3, statistics.median(x[2] for x in f) / 1e3))
    print("\nThe simulator ran at %s in both rows, so its own pacing is not what the load delays. "
          "The node's diagnostics say whether the kernel granted its priority "
          "(`bus thread scheduling`).\n" % ("SCHED_FIFO 60" if sim_raised else
                                              "normal priority (SCHED_FIFO refused)"))


def measure_cpu(workdir, seconds):
    sim = Simulator(workdir, pace=False)
    node = Node(workdir, sim.link, 50.0)
    rates = {}

    def on_diag(msg):
        for s in msg.status:
            if "device " in s.name:
                for kv in s.values:
                    if kv.key == "poll rate achieved [Hz]":
                        rates[s.name.split("device ", 1)[1]] = float(kv.value)
    try:
        node.wait_ready()
        sub = rospy.Subscriber("/diagnostics", DiagnosticArray, on_diag)
        time.sleep(3.0)
        c0, th0, t0 = node.cpu_seconds(), node.thread_cpu_seconds(), time.monotonic()
        w0 = node.bus_thread_wakeups()
        time.sleep(seconds)
        c1, th1, t1 = node.cpu_seconds(), node.thread_cpu_seconds(), time.monotonic()
        wakeups = (node.bus_thread_wakeups() - w0) / (t1 - t0)
        sub.unregister()
    finally:
        node.stop()
        sim.stop()
    threads = {k: 100.0 * (th1.get(k, 0.0) - th0.get(k, 0.0)) / (t1 - t0) for k in th1}
    # The floor: what sleeping and waking that often costs on this machine, by a thread that
    # does nothing else (bench/wakeup_probe.cpp), run alone just after.
    probe = json.loads(subprocess.check_output(
        [executable("modbus_rtu_wakeup_probe"), "--seconds", str(seconds), "--period-us",
         str(int(1e6 / max(wakeups, 1.0)))], text=True))
    threads["floor"] = probe["cpu_percent"]
    threads["wake-ups/s"] = wakeups
    return 100.0 * (c1 - c0) / (t1 - t0), rates, threads


def cpu(workdir, seconds, csv, repeats):
    runs = [measure_cpu(workdir, seconds) for _ in range(repeats)]
    shares = [run[0] for run in runs]
    rates, threads = {}, {}
    for _, r, th in runs:
        for k, v in r.items():
            rates.setdefault(k, []).append(v)
        for k, v in th.items():
            threads.setdefault(k, []).append(v)
    print("## Node CPU while polling 3 devices at 50 Hz (simulator answering at once, 115200, "
          "%d runs)\n" % repeats)
    print("| CPU of one core [%] | of it: bus thread / ROS threads [%] | bus thread wake-ups "
          "[1/s] | a bare thread waking as often [%] | target | achieved poll rates [Hz] |")
    print("|---|---|---|---|---|---|")
    print("| %s | %s / %s | %s | %s | < 5 %% | %s |" % (
        spread(shares, "%.1f"), spread(threads.get("bus thread", []), "%.1f"),
        spread(threads.get("ROS threads", []), "%.1f"), spread(threads["wake-ups/s"], "%.0f"),
        spread(threads["floor"], "%.1f"),
        ", ".join("%s %s" % (k, spread(v, "%.1f")) for k, v in sorted(rates.items()))))
    print("\nMedian (lowest-highest) over the runs; /proc/<pid>/stat (utime + stime) over %.0f s "
          "each. A bus thread sleeps and wakes for each reply, each gap and each poll; the bare "
          "thread (modbus_rtu_wakeup_probe, run alone after each run) does only that, as often: "
          "the machine's floor for that many wake-ups.\n" % seconds)
    csv.write("cpu,3x50Hz,%f,%f,%f\n" % (statistics.median(shares), min(shares), max(shares)))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--calls", type=int, default=500)
    parser.add_argument("--bauds", default="115200,9600",
                        help="latency at each of these bauds (9600: the LC board's factory speed)")
    parser.add_argument("--cpu-seconds", type=float, default=10.0)
    parser.add_argument("--csv", default="node_bench.csv")
    parser.add_argument("--repeats", type=int, default=5, help="runs of each figure")
    parser.add_argument("--hog", type=int, default=0,
                        help="busy processes for the tail-latency table (0: skip it)")
    parser.add_argument("--realtime", type=int, default=50,
                        help="SCHED_FIFO priority compared under --hog")
    args = parser.parse_args()
    with own_master("modbus_rtu_node_bench"):
        with tempfile.TemporaryDirectory() as workdir, open(args.csv, "a") as csv:
            for baud in (int(b) for b in args.bauds.split(",") if b):
                # A 9600 transaction is 12 x longer: fewer calls keep the run short.
                latency(workdir, args.calls if baud > 19200 else max(50, args.calls // 3), csv, baud,
                        args.repeats)
            if args.hog > 0:
                tail_latency(workdir, args.calls, csv, args.hog, args.realtime, args.repeats)
            if args.cpu_seconds > 0:
                cpu(workdir, args.cpu_seconds, csv, args.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
