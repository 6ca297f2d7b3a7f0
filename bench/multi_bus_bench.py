#!/usr/bin/env python3
"""Several buses on one machine (a script, not a test; issue #33 item 2): for 1, 2, 4 and 8
buses, each bus a real bus node (modbus_rtu_bus, in its own namespace /busI) against its own
simulator on its own pty link, the nodes' CPU (per node: mean and max; all nodes together), the
simulators' CPU beside it, whether each bus holds its configured poll rate, and the latency of
SetBool calls spread over the buses in turn. Starts its own rosmaster (bench/node_bench.py's
pieces); prints a markdown table; appends CSV rows to --csv.

    multi_bus_bench.py [--buses 1,2,4,8] [--seconds S] [--calls N] [--repeats R] [--rate HZ]
                       [--pace] [--csv FILE]

Each bus is node_bench.py's: an LC relay board (8), an LD58A08 (1) and a PDU (2) at --rate each
(50 Hz, the CPU table's), 115200 baud, the simulator answering at once unless --pace. Every TCP
port is chosen at run time: the nodes have no share, roscpp and the rosmaster take free ones.
CPU is utime + stime from /proc/<pid>/stat over the same window of --seconds for every process,
with no calls in it; the calls come after the window. A poll rate is the 'polls ok' count of
the node's /diagnostics over that window (from the last report before it to the first after
it), by the reports' own stamps.

CSV row (medians over the runs): multi_bus, buses, CPU per node mean, max, all nodes [% of one
core], the lowest bus's polls held [%], SetBool p50, p95, max [s], all simulators' CPU [%].
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import rospy
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from std_srvs.srv import SetBool

import node_bench

NODE = "bench_bus"  # the same node name in every bus's namespace, as on a robot with /left, /right


def proc_cpu_seconds(pid):
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class Bus:
    """One bus: its simulator on WORKDIR/busI/tty and its node /busI/bench_bus."""

    def __init__(self, workdir, index, rate, pace):
        self.namespace = "/bus%d" % index
        self.node_name = self.namespace + "/" + NODE
        folder = os.path.join(workdir, "bus%d" % index)
        os.makedirs(folder)
        sim_config = os.path.join(folder, "sim.yaml")
        with open(sim_config, "w") as f:
            f.write(node_bench.SIM_YAML % {"baud": 115200})
        self.link = os.path.join(folder, "tty")
        self.sim = subprocess.Popen(
            [node_bench.executable("modbus_rtu_simulator"), "--config", sim_config, "--link",
             self.link] + (["--pace"] if pace else []), stdout=subprocess.PIPE, text=True)
        self.node = None
        try:
            self._start_node(folder, rate)
        except BaseException:
            self.stop()  # this bus's simulator too: the caller only stops the buses it holds
            raise
        self.service = self.node_name + "/relays/out0/set"

    def _start_node(self, folder, rate):
        while True:
            line = self.sim.stdout.readline()
            if not line:
                raise RuntimeError("the simulator of %s stopped before it was ready"
                                   % self.namespace)
            if "simulator ready" in line:
                break
        params = yaml.safe_load(node_bench.BUS_YAML % {"baud": 115200, "rate": rate})
        params["port"] = self.link
        rospy.set_param(self.node_name, params)
        self.log = os.path.join(folder, "node.log")
        with open(self.log, "w") as log:
            self.node = subprocess.Popen(
                [node_bench.executable("modbus_rtu_bus"), "__name:=" + NODE,
                 "__ns:=" + self.namespace], stdout=log, stderr=subprocess.STDOUT)

    def wait_ready(self, timeout=30.0):
        """Until the node's service is up; raises with the node's log when it is not within
        TIMEOUT or the node has exited."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                rospy.wait_for_service(self.service, 0.5)
                return
            except rospy.ROSException:
                if self.node.poll() is not None or time.monotonic() > deadline:
                    with open(self.log) as f:
                        sys.stderr.write(f.read())
                    raise RuntimeError("%s: no %s (node %s)" % (
                        self.namespace, self.service, "exited with %d" % self.node.returncode
                        if self.node.returncode is not None else "still running"))

    def stop(self):
        procs = [p for p in (self.node, self.sim) if p is not None]
        for proc in procs:
            if proc.poll() is None:
                proc.terminate()
        for proc in procs:
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        rospy.delete_param(self.node_name) if rospy.has_param(self.node_name) else None


class Diagnostics:
    """The newest /diagnostics report of each node: {node: [(stamp, {device: (polls ok, polls
    failed, configured Hz)})]}, every report kept."""

    def __init__(self):
        self.lock = threading.Lock()
        self.reports = {}
        self.sub = rospy.Subscriber("/diagnostics", DiagnosticArray, self._on, queue_size=50)

    def _on(self, msg):
        devices = {}
        node = None
        for s in msg.status:
            # diagnostic_updater names a status "<node without its leading />: <name>".
            if ": device " not in s.name:
                continue
            node, device = s.name.split(": device ", 1)
            values = {kv.key: kv.value for kv in s.values}
            devices[device] = (int(values["polls ok"]), int(values["polls failed"]),
                               float(values["poll rate configured [Hz]"]))
        if node is not None:
            with self.lock:
                self.reports.setdefault("/" + node, []).append((msg.header.stamp.to_sec(),
                                                               devices))

    def last_before(self, node, t):
        with self.lock:
            earlier = [r for r in self.reports.get(node, []) if r[0] <= t]
        return earlier[-1] if earlier else None

    def first_after(self, node, t, timeout=5.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self.lock:
                later = [r for r in self.reports.get(node, []) if r[0] >= t]
            if later:
                return later[0]
            time.sleep(0.05)
        return None

    def stop(self):
        self.sub.unregister()


def held(before, after):
    """Per bus: (achieved polls/s of all its devices, configured, polls failed) between two
    reports, or None without both."""
    if before is None or after is None or after[0] <= before[0]:
        return None
    span = after[0] - before[0]
    ok = sum(after[1][d][0] - before[1][d][0] for d in after[1] if d in before[1])
    failed = sum(after[1][d][1] - before[1][d][1] for d in after[1] if d in before[1])
    configured = sum(v[2] for v in after[1].values())
    return ok / span, configured, failed


def measure(workdir, count, args):
    """One run with COUNT buses: a dict of its figures."""
    diagnostics = Diagnostics()
    buses = []
    try:
        for i in range(count):
            buses.append(Bus(workdir, i, args.rate, args.pace))
        for bus in buses:
            bus.wait_ready()
        time.sleep(args.settle)  # polling under way, the first reports out
        t0 = rospy.Time.now().to_sec()
        node0 = [proc_cpu_seconds(b.node.pid) for b in buses]
        sim0 = [proc_cpu_seconds(b.sim.pid) for b in buses]
        w0 = time.monotonic()
        time.sleep(args.seconds)
        node1 = [proc_cpu_seconds(b.node.pid) for b in buses]
        sim1 = [proc_cpu_seconds(b.sim.pid) for b in buses]
        w1 = time.monotonic()
        t1 = rospy.Time.now().to_sec()
        window = w1 - w0
        node_cpu = [100.0 * (b - a) / window for a, b in zip(node0, node1)]
        sim_cpu = [100.0 * (b - a) / window for a, b in zip(sim0, sim1)]
        polls = [held(diagnostics.last_before(b.node_name, t0),
                      diagnostics.first_after(b.node_name, t1)) for b in buses]

        proxies = [rospy.ServiceProxy(b.service, SetBool, persistent=True) for b in buses]
        latencies, failed = [], 0
        for i in range(args.calls):
            want = (i // count) % 2 == 0
            t = time.monotonic()
            try:
                ok = proxies[i % count](want).success
            except rospy.ServiceException:
                ok = False
            if ok:
                latencies.append(time.monotonic() - t)
            else:
                failed += 1
            time.sleep(0.01 + (i % 7) * 0.003)  # land at different points of the poll cycle
        for p in proxies:
            p.close()
    finally:
        diagnostics.stop()
        for bus in buses:
            bus.stop()
    return {"node_cpu": node_cpu, "sim_cpu": sim_cpu, "polls": polls, "latencies": latencies,
            "failed": failed}


def percentile(values, p):
    return node_bench.percentile(values, p) if values else float("nan")


def row(count, runs, csv):
    """The table's row for COUNT buses over its runs; and its CSV row."""
    spread = node_bench.spread
    mean = [statistics.mean(r["node_cpu"]) for r in runs]
    most = [max(r["node_cpu"]) for r in runs]
    total = [sum(r["node_cpu"]) for r in runs]
    sims = [sum(r["sim_cpu"]) for r in runs]
    # Per bus, its achieved polls/s over the runs (median); held = achieved / configured.
    per_bus, lowest, configured, poll_failures = [], [], 0.0, 0
    for b in range(count):
        figures = [r["polls"][b] for r in runs if r["polls"][b] is not None]
        if not figures:
            per_bus.append("-")
            continue
        configured = figures[0][1]
        per_bus.append("%.1f" % statistics.median(f[0] for f in figures))
        poll_failures += sum(f[2] for f in figures)
    for r in runs:
        shares = [p[0] / p[1] for p in r["polls"] if p is not None and p[1] > 0]
        if len(shares) == count:
            lowest.append(100.0 * min(shares))
    latencies = [x for r in runs for x in r["latencies"]]
    failed = sum(r["failed"] for r in runs)
    p50, p95 = 1e3 * percentile(latencies, 50), 1e3 * percentile(latencies, 95)
    top = 1e3 * max(latencies) if latencies else float("nan")
    print("| %d | %s / %s | %s | %s | %s | %s | %d | %.2f / %.2f / %.2f | %d of %d |" % (
        count, spread(mean, "%.1f"), spread(most, "%.1f"), spread(total, "%.1f"),
        spread(sims, "%.1f"), spread(lowest, "%.1f"), ", ".join(per_bus) + " (of %.0f)"
        % configured, poll_failures, p50, p95, top, failed, len(latencies) + failed), flush=True)
    csv.write("multi_bus,%d,%f,%f,%f,%f,%f,%f,%f,%f\n" % (
        count, statistics.median(mean), statistics.median(most), statistics.median(total),
        statistics.median(lowest) if lowest else float("nan"), p50 / 1e3, p95 / 1e3, top / 1e3,
        statistics.median(sims)))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--buses", default="1,2,4,8", help="a row for each of these bus counts")
    parser.add_argument("--seconds", type=float, default=10.0, help="the CPU and poll window")
    parser.add_argument("--settle", type=float, default=3.0,
                        help="s between the nodes' services appearing and the window")
    parser.add_argument("--calls", type=int, default=300,
                        help="SetBool calls of a run, to the buses in turn")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each row")
    parser.add_argument("--rate", type=float, default=50.0, help="poll rate of each device [Hz]")
    parser.add_argument("--pace", action="store_true",
                        help="the simulators pace the line (wire time) instead of answering at once")
    parser.add_argument("--csv", default="multi_bus_bench.csv")
    args = parser.parse_args()
    counts = [int(c) for c in args.buses.split(",") if c]
    load = os.getloadavg()
    with node_bench.own_master("modbus_rtu_multi_bus_bench"):
        with tempfile.TemporaryDirectory() as workdir, open(args.csv, "a") as csv:
            print("## Several buses on one machine (a node and a simulator per bus; 3 devices x "
                  "%g Hz a bus, %s, 115200; %d CPUs; %d run%s a row)\n" % (
                      args.rate, "paced line" if args.pace else "simulator answering at once",
                      os.cpu_count(), args.repeats, "" if args.repeats == 1 else "s"))
            print("| buses | CPU per node, mean / max [% of one core] | CPU of all nodes [%] | "
                  "CPU of all simulators [%] | polls held, the lowest bus [% of configured] | "
                  "achieved polls/s per bus | polls failed | SetBool to the answer p50 / p95 / "
                  "max [ms] | calls failed |")
            print("|---|---|---|---|---|---|---|---|---|", flush=True)
            for count in counts:
                runs = []
                for r in range(args.repeats):
                    # Each run in its own folder: links, locks and logs of one run never meet
                    # another's.
                    run_dir = os.path.join(workdir, "%d_buses_run%d" % (count, r))
                    os.makedirs(run_dir)
                    runs.append(measure(run_dir, count, args))
                row(count, runs, csv)
    print("\nMedian (lowest-highest) over the runs. CPU: /proc/<pid>/stat (utime + stime) over "
          "the same %.0f s window for every node and simulator, no calls in it; 100 %% is one "
          "core. Polls: each device's 'polls ok' in the node's /diagnostics over that window, "
          "summed per bus (configured: 3 x %g Hz). SetBool: %d calls a run (all runs pooled), "
          "to the buses in turn, from the call to its answer in this (Python) process. Load "
          "average at the start: %.2f %.2f %.2f.\n" % (args.seconds, args.rate, args.calls,
                                                       *load))
    return 0


if __name__ == "__main__":
    sys.exit(main())
