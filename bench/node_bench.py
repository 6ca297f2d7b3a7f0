#!/usr/bin/env python3
"""The node's share of the benchmark (a script, not a test): service-to-wire and
service-to-answer latency of SetBool while the node polls three devices, and the node's CPU use
while polling three devices at 50 Hz each. Starts its own rosmaster, the simulator and the node
from the sourced catkin workspace; prints markdown tables; appends CSV rows to --csv.

    node_bench.py [--calls N] [--bauds 115200,9600] [--cpu-seconds S (0: skip)] [--csv FILE]
"""
import argparse
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
  - {type: lc_relay8, address: 255}
  - {type: ld58a08, address: 1}
  - {type: yespeed_pdu, address: 2}
"""

BUS_YAML = """baud: %(baud)d
parity: none
diagnostic_period: 0.5
devices:
  relays: {type: lc_relay8, address: 255, poll_rate: %(rate)s}
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
    """The simulator with --verbose --timestamps; keeps (monotonic time, hex) of every rx."""

    def __init__(self, workdir, pace, baud=115200):
        config = os.path.join(workdir, "sim.yaml")
        with open(config, "w") as f:
            f.write(SIM_YAML % {"baud": baud})
        self.link = os.path.join(workdir, "tty")
        args = [executable("modbus_rtu_simulator"), "--config", config, "--link", self.link,
                "--verbose", "--timestamps"] + (["--pace"] if pace else [])
        self.proc = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
        self.rx = []
        while "simulator ready" not in self.proc.stdout.readline():
            pass
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stdout:
            parts = line.split(" ", 2)
            if len(parts) == 3 and parts[0] == "rx":
                self.rx.append((float(parts[1]), parts[2].strip()))

    def stop(self):
        self.proc.terminate()
        self.proc.wait(10)


class Node:
    def __init__(self, workdir, port, rate, baud=115200, extra_yaml=""):
        config = os.path.join(workdir, "bus.yaml")
        with open(config, "w") as f:
            f.write(BUS_YAML % {"rate": rate, "baud": baud} + extra_yaml)
        subprocess.check_call(["rosparam", "delete", "/bench_bus"], stderr=subprocess.DEVNULL) \
            if self._has_params() else None
        subprocess.check_call(["rosparam", "load", config, "/bench_bus"])
        subprocess.check_call(["rosparam", "set", "/bench_bus/port", port])
        self.log = os.path.join(workdir, "node.log")
        with open(self.log, "w") as log:
            self.proc = subprocess.Popen([executable("modbus_rtu_bus"), "__name:=bench_bus"],
                                         stdout=log, stderr=subprocess.STDOUT)

    def wait_ready(self):
        try:
            rospy.wait_for_service("/bench_bus/relays/out0/set", 30)
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

    def stop(self):
        self.proc.terminate()
        self.proc.wait(20)


def percentile(values, p):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(p / 100.0 * (len(ordered) - 1))))]


def latency(workdir, calls, csv, baud):
    sim = Simulator(workdir, pace=True, baud=baud)
    node = Node(workdir, sim.link, 10.0, baud)
    try:
        node.wait_ready()
        pump = rospy.ServiceProxy("/bench_bus/relays/out0/set", SetBool, persistent=True)
        time.sleep(2.0)  # polling under way
        wire, answer, failed = [], [], 0
        for i in range(calls):
            want = i % 2 == 0
            frame = "FF 05 00 00 %s" % ("FF 00" if want else "00 00")
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
    # One transaction's wire time at the baud, 8N1: the longest poll, FC04 5 registers (8 + 15
    # bytes) with t3.5 after the request and after the reply (1.75 ms above 19200 baud).
    t35 = 3.5 * 11 / baud if baud <= 19200 else 0.00175
    transaction = (8 + 15) * 10.0 / baud + 2 * t35
    target = 0.002 + transaction
    print("## Latency of SetBool while polling 3 devices at 10 Hz (paced %d line, %d calls)\n"
          % (baud, calls))
    print("| from the call to | p50 [ms] | p99 [ms] | max [ms] | target p99 [ms] |")
    print("|---|---|---|---|---|")
    for name, values in (("the frame on the line", wire), ("the answer", answer)):
        if not values:
            print("| %s | - | - | - | |" % name)
            continue
        print("| %s | %.2f | %.2f | %.2f | %s |" % (
            name, 1e3 * percentile(values, 50), 1e3 * percentile(values, 99), 1e3 * max(values),
            "%.2f (2 ms + one transaction, %.2f ms)" % (1e3 * target, 1e3 * transaction)
            if name.startswith("the frame") else ""))
        csv.write("latency_%d,%s,%f,%f,%f\n" % (baud, name.replace(" ", "_"), percentile(values, 50),
                                              percentile(values, 99), target))
    print("\n%d of %d calls matched to their frame; %d failed.\n" % (len(wire), calls, failed))


def cpu(workdir, seconds, csv):
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
        c0, t0 = node.cpu_seconds(), time.monotonic()
        time.sleep(seconds)
        c1, t1 = node.cpu_seconds(), time.monotonic()
        sub.unregister()
    finally:
        node.stop()
        sim.stop()
    share = 100.0 * (c1 - c0) / (t1 - t0)
    print("## Node CPU while polling 3 devices at 50 Hz (simulator answering at once, 115200)\n")
    print("| CPU of one core | target | achieved poll rates [Hz] |")
    print("|---|---|---|")
    print("| %.1f %% | < 5 %% | %s |" % (share, ", ".join(
        "%s %.1f" % (k, v) for k, v in sorted(rates.items()))))
    print("\nMeasured from /proc/<pid>/stat (utime + stime) over %.0f s.\n" % (t1 - t0))
    csv.write("cpu,3x50Hz,%f,,\n" % share)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--calls", type=int, default=500)
    parser.add_argument("--bauds", default="115200,9600",
                        help="latency at each of these bauds (9600: the LC board's factory speed)")
    parser.add_argument("--cpu-seconds", type=float, default=10.0)
    parser.add_argument("--csv", default="node_bench.csv")
    args = parser.parse_args()
    port = free_port()
    os.environ["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
    master = subprocess.Popen(["rosmaster", "--core", "-p", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        time.sleep(1.5)
        rospy.init_node("modbus_rtu_node_bench", anonymous=True, disable_signals=True)
        logging.getLogger("rosout").setLevel(logging.ERROR)  # keep the tables clean
        with tempfile.TemporaryDirectory() as workdir, open(args.csv, "a") as csv:
            for baud in (int(b) for b in args.bauds.split(",") if b):
                # A 9600 transaction is 12 x longer: fewer calls keep the run short.
                latency(workdir, args.calls if baud > 19200 else max(50, args.calls // 3), csv, baud)
            if args.cpu_seconds > 0:
                cpu(workdir, args.cpu_seconds, csv)
    finally:
        master.terminate()
        master.wait(10)
    return 0


if __name__ == "__main__":
    sys.exit(main())
