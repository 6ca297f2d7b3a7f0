#!/usr/bin/env python3
"""Where the line's time goes (a script, not a test): the node polls three devices as fast as the
line allows against the paced simulator. Two sets of timestamps on one clock (CLOCK_MONOTONIC)
split each transaction: the simulator's (--timestamps: when a request's bytes reached it, when it
wrote a reply's) and the node's own (wire_log: when it wrote a request, when it read a reply's
first and last byte). The parts:

  request and reply wire time (characters at the baud, 8N1),
  the two required silences (t3.5 after the request and after the reply),
  the simulator's turnaround (its reply began later than the request's end + t3.5; from the
  node's write, so the simulator's own wake-up is in it),
  the driver's turnaround (from the reply's last byte, as the simulator wrote it, to the node's
  write of the next request, less the t3.5 the driver must keep), and within it
    its wake-up: the reply's last byte written -> the node's read of it returned (the kernel
    delivering it and scheduling the bus thread), and
    its own work: that read -> the next write, less t3.5 (decoding, scheduling, the gap's
    timing), itself split (wire_log's late= and guard=) into
      the gap's sleep waking late: the machine's timer and scheduler,
      the late-reply guard: after a failed transaction with a slave, its next different
      request waits until the line has been quiet for late_reply_guard (by design), and
      the rest: the driver's code past the gap, and any preemption of it.
  Beside them, the bus thread's CPU time from the reply's read to the next request's write
  (wire_log's cpu=): the driver's code per transaction, most of it run inside t3.5 where it
  costs the line nothing (so it has no share).

Beside each run, modbus_rtu_wakeup_probe (bench/wakeup_probe.cpp) sleeps to a deadline every
t3.5 at the bus thread's priority and measures how late the machine wakes a thread that does
nothing: the machine's share, apart from the driver.

Prints p50 / p99 / max of each, and each share of the elapsed time, as the median
(lowest-highest) of --repeats runs. Targets: the driver's turnaround p50 < 100 us and p99 < 1 ms;
its share of the line below 2 %. Starts its own rosmaster.

    line_attribution.py [--seconds S] [--repeats R] [--bauds 115200,9600] [--csv FILE]
"""
import argparse
import bisect
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from node_bench import (Node, Simulator, executable, own_master,  # noqa: E402
                        percentile, raise_simulator, spread)


def character(baud):
    return 10.0 / baud  # 8N1


def silence(baud):
    return 3.5 * character(baud) if baud <= 19200 else 0.00175


def frame_bytes(hexed):
    return len(hexed.split())


def read_wire_log(path):
    """The node's frames: (tx or rx, first, last, hex, the bus thread's CPU seconds, how late
    the gap's sleep before a request woke) in the order it sent and read them."""
    events = []
    with open(path) as f:
        for line in f:
            parts = line.split(" ", 3)
            if len(parts) == 4 and parts[0] in ("tx", "rx") and " cpu=" in parts[3]:
                hexed, cpu = parts[3].split(" cpu=")
                cpu, _, late = cpu.partition(" late=")
                late, _, guard = late.partition(" guard=")
                events.append((parts[0], float(parts[1]), float(parts[2]), hexed, float(cpu),
                               float(late or 0), float(guard or 0)))
    return events


# Within the driver's turnaround: wake-up + own work; own work = late sleep + guard + the rest.
LATE, GUARD, REST, CPU = (
    "driver: own work, the gap's sleep woke late",
    "driver: own work, the late-reply guard after a failure", "driver: own work, the rest",
    "driver: CPU time, reply read to next request")
DRIVER_PARTS = ("driver: wake-up", "driver: own work", LATE, GUARD, REST, CPU)


def attribute(sim_frames, node_frames, baud):
    """Per transaction (the node's request, the reply, the node's next request) the parts in
    seconds, and the elapsed time they cover. A transaction is used when both sides saw it whole
    (the simulator's request and reply match the node's bytes)."""
    ch, gap = character(baud), silence(baud)
    parts = {k: [] for k in ("request wire", "reply wire", "required silences",
                             "simulator turnaround", "driver turnaround") + DRIVER_PARTS}
    start = end = None
    sim_times = [f[1] for f in sim_frames]
    for i in range(len(node_frames) - 2):
        (d0, sent, _, rq_hex, _, _, _), (d1, _, read_last, rp_hex, read_cpu, _, _), \
            (d2, next_sent, _, _, next_cpu, late, guard) = node_frames[i:i + 3]
        if (d0, d1, d2) != ("tx", "rx", "tx"):
            continue  # a broadcast or a lost reply: not a clean transaction
        # The simulator's view of the same request: the first it read after the node wrote it
        # and before the node read the reply (the same bytes recur every few transactions, and
        # the two logs need not start together).
        k = bisect.bisect_left(sim_times, sent - 1e-4)
        while k < len(sim_frames) and sim_times[k] <= read_last and \
                (sim_frames[k][0], sim_frames[k][3]) != ("rx", rq_hex):
            k += 1
        if k + 1 >= len(sim_frames) or sim_times[k] > read_last:
            continue
        reply = sim_frames[k + 1]
        if reply[0] != "tx" or reply[3] != rp_hex or reply[2] > read_last:
            continue
        request_wire = frame_bytes(rq_hex) * ch
        reply_wire = frame_bytes(rp_hex) * ch
        # The reply's first byte is written once its last bit is on the line: one character in.
        reply_start = reply[1] - ch
        parts["request wire"].append(request_wire)
        parts["reply wire"].append(reply_wire)
        parts["required silences"].append(2 * gap)
        parts["simulator turnaround"].append(max(0.0, reply_start - (sent + request_wire + gap)))
        parts["driver turnaround"].append(next_sent - reply[2] - gap)
        parts["driver: wake-up"].append(read_last - reply[2])
        own = next_sent - read_last - gap
        guard = min(guard, max(own, 0.0))
        late = min(late, max(own - guard, 0.0))
        parts["driver: own work"].append(own)
        parts[LATE].append(late)
        parts[GUARD].append(guard)
        parts[REST].append(own - late - guard)
        # Never below 0: a spin preempted would be counted as spun for longer than it ran.
        parts[CPU].append(max(0.0, next_cpu - read_cpu))
        start = sent if start is None else start
        end = next_sent
    return parts, (end - start) if start is not None else 0.0


def stolen_seconds():
    """CPU time the hypervisor gave to others while this VM wanted it (/proc/stat's steal, summed
    over the CPUs): a stall no process here can cause or prevent."""
    with open("/proc/stat") as f:
        fields = f.readline().split()
    return int(fields[8]) / os.sysconf("SC_CLK_TCK") if len(fields) > 8 else 0.0


def run_once(workdir, seconds, baud, realtime):
    sim = Simulator(workdir, pace=True, baud=baud)
    if realtime:
        raise_simulator(sim)
    # Every device always due: the line is full.
    wire_log = os.path.join(workdir, "wire.log")
    node = Node(workdir, sim.link, 1000.0, baud,
                "realtime_priority: %d\nwire_log: %s\n" % (realtime, wire_log))
    try:
        node.wait_ready()
        time.sleep(2.0)  # past the first polls, which read more
        first = len(sim.frames)
        began, stolen = time.monotonic(), stolen_seconds()
        probe = subprocess.Popen(
            [executable("modbus_rtu_wakeup_probe"), "--seconds", str(seconds), "--period-us",
             str(int(silence(baud) * 1e6)), "--fifo", str(realtime)], stdout=subprocess.PIPE,
            text=True)
        time.sleep(seconds)
        frames = list(sim.frames[first:])
        machine = json.loads(probe.communicate(timeout=30)[0])
        machine["steal_percent"] = 100.0 * (stolen_seconds() - stolen) / (
            (time.monotonic() - began) * os.cpu_count())
    finally:
        node.stop()
        sim.stop()
    # Only the window measured: the node's last transactions before it stops wait for its
    # shutdown, not for the line.
    node_frames = [f for f in read_wire_log(wire_log) if began - 0.1 <= f[1] <= began + seconds]
    parts, elapsed = attribute(frames, node_frames, baud)
    return parts, elapsed, machine


def report(baud, runs, csv, realtime):
    names = list(runs[0][0].keys())
    print("## Where the line's time goes at %d baud (the node polls 3 devices back to back, "
          "paced simulator, %d runs%s)\n" % (baud, len(runs), (
              ", bus thread and simulator at SCHED_FIFO: the machine's other load set aside"
              if realtime else "")))
    print("| part | p50 [us] | p99 [us] | max [us] | share of the time [%] |")
    print("|---|---|---|---|---|")
    for name in names:
        p50 = [1e6 * percentile(parts[name], 50) for parts, _, _ in runs if parts[name]]
        p99 = [1e6 * percentile(parts[name], 99) for parts, _, _ in runs if parts[name]]
        top = [1e6 * max(parts[name]) for parts, _, _ in runs if parts[name]]
        share = [100.0 * sum(parts[name]) / elapsed for parts, elapsed, _ in runs
                 if elapsed > 0 and name != CPU]
        print("| %s | %s | %s | %s | %s |" % (name, spread(p50, "%.0f"), spread(p99, "%.0f"),
                                               spread(top, "%.0f"), spread(share, "%.2f")))
        if p50:
            csv.write("attribution_%d%s,%s,%f,%f,%f\n" % (baud, "_rt" if realtime else "",
                                                         name.replace(" ", "_"),
                                                       statistics.median(p50) / 1e6,
                                                       statistics.median(p99) / 1e6,
                                                       statistics.median(share) if share
                                                       else float("nan")))
    machine = [m for _, _, m in runs]
    late = {k: [m["late_us"][k] for m in machine] for k in ("p50", "p99", "max")}
    print("| machine: a bare thread's wake-up lateness (%s) | %s | %s | %s | - |" % (
        machine[0]["policy"], spread(late["p50"], "%.0f"), spread(late["p99"], "%.0f"),
        spread(late["max"], "%.0f")))
    print("| machine: CPU time the hypervisor took (steal) [%% of the CPUs] | - | - | - | %s |" %
          spread([m["steal_percent"] for m in machine], "%.2f"))
    csv.write("attribution_%d%s,machine_wakeup_lateness,%f,%f,\n" % (
        baud, "_rt" if realtime else "", statistics.median(late["p50"]) / 1e6,
        statistics.median(late["p99"]) / 1e6))
    transactions = [len(parts["driver turnaround"]) for parts, _, _ in runs]
    verdict = lambda ok: "met" if ok else "NOT met"  # noqa: E731

    def judged(name):
        p50 = statistics.median(1e6 * percentile(p[name], 50) for p, _, _ in runs)
        p99 = statistics.median(1e6 * percentile(p[name], 99) for p, _, _ in runs)
        share = statistics.median(100.0 * sum(p[name]) / e for p, e, _ in runs if e > 0)
        return "p50 %.0f us (%s), p99 %.0f us (%s), share %.2f %% (%s)" % (
            p50, verdict(p50 < 100), p99, verdict(p99 < 1000), share, verdict(share < 2.0))

    print("\n%s transactions per run. Targets p50 < 100 us, p99 < 1000 us, share of the line "
          "< 2 %%:\n\n- the driver's own work less the machine's lateness in waking it from the "
          "gap's sleep and less the late-reply guard after a failed transaction: %s;\n"
          "- the driver's own work (its read of the reply's last byte to its write of the next "
          "request, less t3.5): %s;\n- the driver's turnaround as the issue defines it "
          "(the reply's last byte written by the simulator to the next request written, less "
          "t3.5), which adds the kernel's delivery of the reply through the pty and the bus "
          "thread's wake-up: %s.\n\nThe shares add up to the line's use, the driver's two parts "
          "counted once (in its turnaround): what is left is time no part claims (rounding, "
          "frames not paired). The machine's row: modbus_rtu_wakeup_probe sleeping to a deadline "
          "every t3.5 beside the node, at the bus thread's priority.\n" % (
              spread(transactions, "%d"), judged(REST),
              judged("driver: own work"), judged("driver turnaround")))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=5.0, help="measured per run")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--bauds", default="115200,9600")
    parser.add_argument("--csv", default="line_attribution.csv")
    parser.add_argument("--realtime", type=int, default=0,
                        help="also measure with the bus thread and the simulator at SCHED_FIFO P")
    args = parser.parse_args()
    with own_master("modbus_rtu_line_attribution"):
        with tempfile.TemporaryDirectory() as workdir, open(args.csv, "a") as csv:
            for baud in (int(b) for b in args.bauds.split(",") if b):
                for realtime in sorted({0, args.realtime}):
                    runs = [run_once(workdir, args.seconds, baud, realtime)
                            for _ in range(args.repeats)]
                    report(baud, runs, csv, realtime)
    return 0


if __name__ == "__main__":
    sys.exit(main())
