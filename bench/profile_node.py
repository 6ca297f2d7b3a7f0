#!/usr/bin/env python3
"""Where the node's CPU goes (a script, not a test): perf samples the running node while it
polls three devices at 50 Hz each (the simulator answering at once, 115200), and each sample is
put in one part by the functions on its call stack: the poll path on the bus thread (link,
framing, devices, scheduling), ROS publishing, diagnostics, service and topic callbacks, and
roscpp's own threads. Starts its own rosmaster, the simulator and the node (node_bench.py's
pieces); prints a markdown table; appends CSV rows to --csv.

    profile_node.py [--seconds S] [--frequency HZ] [--csv FILE]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import node_bench

# A sample belongs to the first part whose marker is on its stack (innermost frames first
# would split one publish into serialization and socket writes; the part is what it serves).
PARTS = [
    ("diagnostics", ("diagnostic_updater::", "DiagnosticStatusWrapper", "BusDiagnostics")),
    ("ROS publishing", ("ros::Publisher::publish", "publishShared", "ros::TopicManager::publish",
                        "ros::Publication::", "DigitalStatesPublisher", "ros::serialization::")),
    ("service and command callbacks", ("ros::ServiceCallbackHelper", "ros::SubscriptionQueue",
                                       "ros::ServiceClientLink", "ros::ServicePublication")),
    ("roscpp's transport and timers", ("ros::PollManager", "ros::PollSet", "ros::Connection::",
                                       "ros::TransportTCP", "XmlRpc::", "ros::TimerManager",
                                       "ros::CallbackQueue", "ros::ROSOutAppender")),
]
BUS_THREAD = "modbus_bus"


def samples(perf_data):
    """(thread name, [frames innermost first, each 'symbol (dso)']) of each sample."""
    text = subprocess.run(["perf", "script", "-i", perf_data, "-F", "comm,tid,ip,sym,dso"],
                          capture_output=True, text=True, check=True).stdout
    for block in text.split("\n\n"):
        lines = [l for l in block.splitlines() if l.strip()]
        if not lines:
            continue
        comm = lines[0].split()[0]
        frames = [l.strip().split(" ", 1)[-1] for l in lines[1:]]
        yield comm, frames


def part_of(comm, frames):
    stack = "\n".join(frames)
    for name, markers in PARTS:
        if any(m in stack for m in markers):
            return name
    if comm == BUS_THREAD:
        return "poll path (bus thread: link, framing, devices, scheduling)"
    return "other"


def profile(workdir, seconds, frequency):
    sim = node_bench.Simulator(workdir, pace=False)
    node = node_bench.Node(workdir, sim.link, 50.0)
    data = os.path.join(workdir, "perf.data")
    try:
        node.wait_ready()
        time.sleep(3.0)  # polling under way
        c0, t0 = node.cpu_seconds(), time.monotonic()
        # DWARF call graphs: the node is built without frame pointers.
        subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-F", str(frequency),
                        "--call-graph", "dwarf,16384", "-p", str(node.proc.pid), "-o", data,
                        "--", "sleep", str(seconds)], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        cpu = 100.0 * (node.cpu_seconds() - c0) / (time.monotonic() - t0)
    finally:
        node.stop()
        sim.stop()
    counts, kernel, leaves = {}, {}, {}
    for comm, frames in samples(data):
        part = part_of(comm, frames)
        counts[part] = counts.get(part, 0) + 1
        if frames and "[kernel.kallsyms]" in frames[0]:
            kernel[part] = kernel.get(part, 0) + 1
        leaf = frames[0].rsplit(" (", 1)[0].split("+0x")[0] if frames else "?"
        leaves[leaf] = leaves.get(leaf, 0) + 1
    return cpu, counts, kernel, leaves


def perf_problem():
    """Why perf cannot sample here, or "". Debian 11's perf is a wrapper that runs the perf of
    the running kernel's version: in a container or chroot on a newer kernel there is none."""
    try:
        done = subprocess.run(["perf", "--version"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as e:
        return "perf: %s" % e
    if done.returncode != 0:
        return "perf: %s" % (done.stderr or done.stdout).strip().splitlines()[0]
    return ""


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--frequency", type=int, default=4999, help="perf samples per second")
    parser.add_argument("--csv", default="profile_node.csv")
    args = parser.parse_args()
    problem = perf_problem()
    if problem:
        print("profile_node.py: not measured: %s" % problem, file=sys.stderr)
        return 77  # scripts/benchmark.sh: skipped, with the reason
    with node_bench.own_master("modbus_rtu_profile_node"):
        with tempfile.TemporaryDirectory() as workdir, open(args.csv, "a") as csv:
            cpu, counts, kernel, leaves = profile(workdir, args.seconds, args.frequency)
            total = sum(counts.values())
            print("## Where the node's CPU goes while polling 3 devices at 50 Hz (perf, %.0f s, "
                  "%d samples)\n" % (args.seconds, total))
            print("| part | of the node's samples [%] | CPU of one core [%] | of it in the "
                  "kernel [%] |")
            print("|---|---|---|---|")
            for part, n in sorted(counts.items(), key=lambda kv: -kv[1]):
                share = n / total if total else 0.0
                print("| %s | %.1f | %.2f | %.0f |" % (part, 100 * share, cpu * share,
                                                       100.0 * kernel.get(part, 0) / n))
                csv.write("profile,%s,%f,%f,\n" % (part, 100 * share, cpu * share))
            print("\nThe node used %.1f %% of one core over the window (/proc/<pid>/stat). A sample "
                  "is put in the first part whose functions are on its stack; 'in the kernel': "
                  "the sample was taken in a system call or the scheduler. perf's own cost of "
                  "taking the samples is in the figure.\n" % cpu)
            print("| function the sample was taken in (top 10) | of the node's samples [%] |")
            print("|---|---|")
            for leaf, n in sorted(leaves.items(), key=lambda kv: -kv[1])[:10]:
                print("| `%s` | %.1f |" % (leaf[:90], 100.0 * n / total))
            print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
