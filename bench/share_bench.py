#!/usr/bin/env python3
"""The share's benchmark row (a script, not a test): the latency of a request through the
node's Modbus TCP share (FC01, 8 coils of the LC board) while the node polls three devices at
10 Hz on a paced line, from the client's send to its complete reply. Starts its own rosmaster,
the simulator and the node (bench/node_bench.py's pieces); prints a markdown table; appends CSV
rows to --csv.

    share_bench.py [--requests N] [--bauds 115200,9600] [--csv FILE]
"""
import argparse
import os
import sys
import tempfile
import time

import node_bench

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "test"))
from mbap_client import MbapClient, read_pdu  # noqa: E402  (test/mbap_client.py)


# The LC board of node_bench's bus (its address there, not its factory 255: the share answers
# exception 0B for a unit no device of the bus has).
RELAYS_UNIT = 8


def latency(workdir, requests, csv, baud):
    sim = node_bench.Simulator(workdir, pace=True, baud=baud)
    share_port = node_bench.free_port()
    node = node_bench.Node(workdir, sim.link, 10.0, baud,
                           extra_yaml='share: {listen: "127.0.0.1:%d"}\n' % share_port)
    times = []
    try:
        node.wait_ready()
        time.sleep(2.0)  # polling under way
        with MbapClient(share_port, RELAYS_UNIT, timeout=10) as client:
            for i in range(requests):
                t0 = time.monotonic()
                client.transact(read_pdu(0, 8))  # FC01, 8 coils; raises on a wrong answer
                times.append(time.monotonic() - t0)
                time.sleep(0.01 + (i % 7) * 0.003)  # land at different points of the poll cycle
    finally:
        node.stop()
        sim.stop()
    p50, p99 = node_bench.percentile(times, 50), node_bench.percentile(times, 99)
    print("| %d | %d | %.2f | %.2f | %.2f |" % (baud, len(times), 1e3 * p50, 1e3 * p99,
                                                1e3 * max(times)))
    csv.write("share_latency_%d,fc01_8_coils,%f,%f,\n" % (baud, p50, p99))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--requests", type=int, default=300)
    parser.add_argument("--bauds", default="115200,9600")
    parser.add_argument("--csv", default="share_bench.csv")
    args = parser.parse_args()
    with node_bench.own_master("modbus_rtu_share_bench"):
        print("## Latency of a shared request (Modbus TCP, FC01 8 coils) while the node polls "
              "3 devices at 10 Hz (paced line)\n")
        print("| baud | requests | p50 [ms] | p99 [ms] | max [ms] |")
        print("|---|---|---|---|---|")
        with tempfile.TemporaryDirectory() as workdir, open(args.csv, "a") as csv:
            for baud in (int(b) for b in args.bauds.split(",") if b):
                latency(workdir, args.requests if baud > 19200 else max(50, args.requests // 3),
                        csv, baud)
        print("\nFrom the client's send to its complete reply: the wait for the transaction on the "
              "line (a poll), then the request's own transaction.\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
