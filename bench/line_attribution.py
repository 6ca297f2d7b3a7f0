#!/usr/bin/env python3
"""Where the line's time goes (a script, not a test): the node polls three devices as fast as the
line allows against the paced simulator, and the simulator's timestamps of every frame's first
and last byte split each transaction into

  request and reply wire time (characters at the baud, 8N1),
  the two required silences (t3.5 after the request and after the reply),
  the simulator's turnaround (its reply began later than the request's end + t3.5),
  the driver's turnaround (from the reply's last byte to the next request's first byte, less
  the t3.5 the driver must keep): its wake-up, decoding, scheduling and the pty both ways.

Prints p50 / p99 / max of each, and each share of the elapsed time, as the median
(lowest-highest) of --repeats runs. Targets: the driver's turnaround p50 < 100 us and p99 < 1 ms;
its share of the line below 2 %. Starts its own rosmaster.

    line_attribution.py [--seconds S] [--repeats R] [--bauds 115200,9600] [--csv FILE]
"""
import argparse
import os
import statistics
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from node_bench import (Node, Simulator, own_master, percentile,  # noqa: E402
                        raise_simulator, spread)


def character(baud):
    return 10.0 / baud  # 8N1


def silence(baud):
    return 3.5 * character(baud) if baud <= 19200 else 0.00175


def frame_bytes(hexed):
    return len(hexed.split())


def attribute(frames, baud):
    """Per transaction (request followed by its reply, then the next request) the parts in
    seconds, and the elapsed time they cover."""
    ch, gap = character(baud), silence(baud)
    parts = {k: [] for k in ("request wire", "reply wire", "required silences",
                             "simulator turnaround", "driver turnaround")}
    start = end = None
    for i in range(len(frames) - 2):
        (d0, rq_first, _, rq_hex), (d1, tx_first, tx_last, tx_hex), (d2, next_first, _, _) = \
            frames[i:i + 3]
        if (d0, d1, d2) != ("rx", "tx", "rx"):
            continue  # a broadcast or a lost reply: not a clean transaction
        request_wire = frame_bytes(rq_hex) * ch
        reply_wire = frame_bytes(tx_hex) * ch
        # The reply's first byte is written once its last bit is on the line: one character in.
        reply_start = tx_first - ch
        parts["request wire"].append(request_wire)
        parts["reply wire"].append(reply_wire)
        parts["required silences"].append(2 * gap)
        parts["simulator turnaround"].append(max(0.0, reply_start - (rq_first + request_wire + gap)))
        parts["driver turnaround"].append(next_first - tx_last - gap)
        start = rq_first if start is None else start
        end = next_first
    return parts, (end - start) if start is not None else 0.0


def run_once(workdir, seconds, baud, realtime):
    sim = Simulator(workdir, pace=True, baud=baud)
    if realtime:
        raise_simulator(sim)
    # Every device always due: the line is full.
    node = Node(workdir, sim.link, 1000.0, baud, "realtime_priority: %d\n" % realtime)
    try:
        node.wait_ready()
        time.sleep(2.0)  # past the first polls, which read more
        first = len(sim.frames)
        time.sleep(seconds)
        frames = list(sim.frames[first:])
    finally:
        node.stop()
        sim.stop()
    return attribute(frames, baud)


def report(baud, runs, csv, realtime):
    names = list(runs[0][0].keys())
    print("## Where the line's time goes at %d baud (the node polls 3 devices back to back, "
          "paced simulator, %d runs%s)\n" % (baud, len(runs), (
              ", bus thread and simulator at SCHED_FIFO: the machine's other load set aside"
              if realtime else "")))
    print("| part | p50 [us] | p99 [us] | max [us] | share of the time [%] |")
    print("|---|---|---|---|---|")
    for name in names:
        p50 = [1e6 * percentile(parts[name], 50) for parts, _ in runs if parts[name]]
        p99 = [1e6 * percentile(parts[name], 99) for parts, _ in runs if parts[name]]
        top = [1e6 * max(parts[name]) for parts, _ in runs if parts[name]]
        share = [100.0 * sum(parts[name]) / elapsed for parts, elapsed in runs if elapsed > 0]
        print("| %s | %s | %s | %s | %s |" % (name, spread(p50, "%.0f"), spread(p99, "%.0f"),
                                               spread(top, "%.0f"), spread(share, "%.2f")))
        if p50:
            csv.write("attribution_%d%s,%s,%f,%f,%f\n" % (baud, "_rt" if realtime else "",
                                                         name.replace(" ", "_"),
                                                       statistics.median(p50) / 1e6,
                                                       statistics.median(p99) / 1e6,
                                                       statistics.median(share)))
    transactions = [len(parts["driver turnaround"]) for parts, _ in runs]
    driver_p50 = statistics.median(1e6 * percentile(p["driver turnaround"], 50) for p, _ in runs)
    driver_p99 = statistics.median(1e6 * percentile(p["driver turnaround"], 99) for p, _ in runs)
    driver_share = statistics.median(100.0 * sum(p["driver turnaround"]) / e for p, e in runs)
    verdict = lambda ok: "met" if ok else "NOT met"  # noqa: E731
    print("\n%s transactions per run. Targets: driver turnaround p50 < 100 us (%s), p99 < 1000 "
          "us (%s); the driver's share of the line < 2 %% (%s, %.2f %%). The shares add up to "
          "the line's use: what is left is time no part claims (rounding, frames not paired).\n"
          % (spread(transactions, "%d"), verdict(driver_p50 < 100), verdict(driver_p99 < 1000),
             verdict(driver_share < 2.0), driver_share))


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
