#!/usr/bin/env python3
"""Instructions per transaction of the node (issue 50), a figure that does not move with the
machine's load as CPU % does: the node runs under `valgrind --tool=callgrind` while it polls three
devices at 50 Hz each (node_bench.py's simulator and bus, 115200, the simulator answering at
once); after a warm-up, callgrind counts the instructions of a window, and the simulator counts
the requests in it. Prints, per build: the transactions, the instructions per transaction of the
bus thread and of the whole node, the bus thread's allocations per transaction (calls to malloc,
calloc and realloc, from callgrind's call counts), its top 10 functions (self cost) and the
package's functions that allocate most (each allocation put on the first of them above it). Valgrind
runs the node about 50 times slower, so it polls less often than asked: the figure is per
transaction, not per second. Starts its own rosmaster, simulator and node.

    callgrind_node.py [--seconds S] [--warmup S] [--node EXE ...] [--keep DIR]

Runs the three devices together, then each alone (the instructions of a poll of each device
type). Needs valgrind (not on scripts/debian_packages.txt: this tool is not part of
scripts/benchmark.sh yet).

--node: another build's modbus_rtu_bus (its libraries beside it), measured after this one; each
build runs alone, one after the other.
"""
import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

import node_bench

BUS_MARKERS = ("BusScheduler::", "modbus_rtu_driver::Link::")
# A service each configuration has once the node is up.
SERVICE = {None: "relays/out0/set", "relays": "relays/out0/set", "pwm_board": "pwm_board/out0/set",
           "pdu": "pdu/out0/set"}
DEVICES = [(None, "all three"), ("relays", "LC relay board (lc_relay8)"),
           ("pwm_board", "LD58A08 (ld58a08)"), ("pdu", "Yespeed PDU (yespeed_pdu)")]


def thread_costs(path):
    """(total instructions, {function: self instructions}) of one callgrind output file."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=no", "--auto=no", "--threshold=100",
                           path],
                          capture_output=True, text=True, check=True).stdout
    total, functions = 0, {}
    for line in text.splitlines():
        m = re.match(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+PROGRAM TOTALS", line) or \
            re.match(r"^\s*([\d,]+)\s+PROGRAM TOTALS", line)
        if m:
            total = int(m.group(1).replace(",", ""))
            continue
        m = re.match(r"^\s*([\d,]+)\s+(?:\(\s*[\d.]+%\)\s+)?(\S.*?):(.*?)(?: \[.*\])?$", line)
        if m and not line.lstrip().startswith("Ir"):
            name = m.group(3).strip()
            functions[name] = functions.get(name, 0) + int(m.group(1).replace(",", ""))
    return total, functions


ALLOCATORS = ("malloc", "calloc", "realloc")
NEW = ("operator new(unsigned long)", "operator new[](unsigned long)")


def allocations(path):
    """(calls to malloc, calloc and realloc; {function: allocations}) of one callgrind output
    file, from its call records (`cfn=` then `calls=N`). Each allocation is put on the first
    function of this package (modbus_rtu_driver::) above it: a library function's (std::string,
    std::vector, operator new) go to its callers in proportion to their calls."""
    names, fn, callee, total = {}, None, None, 0
    own, incoming = {}, {}  # allocations made by each function; {callee: {caller: calls}}

    def name_of(ref):
        m = re.match(r"\((\d+)\)(?: (.*))?$", ref)
        if not m:
            return ref
        if m.group(2) is not None:
            names[m.group(1)] = m.group(2)
        return names.get(m.group(1), ref)

    with open(path, errors="replace") as f:
        for line in f:
            if line.startswith("fn="):
                fn = name_of(line[3:].strip())
            elif line.startswith("cfn="):
                callee = name_of(line[4:].strip())
            elif line.startswith("calls=") and callee is not None:
                n = int(line[6:].split()[0])
                if callee in ALLOCATORS:
                    total += n
                    own[fn] = own.get(fn, 0) + n
                else:
                    incoming.setdefault(callee, {})
                    incoming[callee][fn] = incoming[callee].get(fn, 0) + n
                callee = None
    for _ in range(30):  # up the call graph until each count sits on one of ours (or a root)
        moved = {}
        for f, n in own.items():
            callers = incoming.get(f, {})
            if "modbus_rtu_driver::" in f or not callers:
                moved[f] = moved.get(f, 0) + n
                continue
            calls = sum(callers.values())
            for caller, k in callers.items():
                moved[caller] = moved.get(caller, 0) + n * k / calls
        if moved == own:
            break
        own = moved
    return total, own


def measure(workdir, exe, seconds, warmup, only=None):
    sim = node_bench.Simulator(workdir, pace=False)
    out = os.path.join(workdir, "callgrind.out")
    env = dict(os.environ)
    if exe:
        env["LD_LIBRARY_PATH"] = os.path.dirname(os.path.abspath(exe))
    prefix = ["valgrind", "--tool=callgrind", "--instr-atstart=no", "--separate-threads=yes",
              "--callgrind-out-file=" + out + ".%p"]
    node = node_bench.Node(workdir, sim.link, 50.0, prefix=prefix, exe=exe, env=env, only=only)
    try:
        node.wait_ready(timeout=180, service=SERVICE[only])
        time.sleep(warmup)  # polling under way, start-up done
        # Instrumented from here (not from the start: a faster start-up), counts zeroed.
        for option in (["-i", "on"], ["-z"]):
            subprocess.run(["callgrind_control"] + option + [str(node.proc.pid)], check=True,
                           stdout=subprocess.DEVNULL)
        first = len(sim.rx)
        time.sleep(seconds)
        transactions = len(sim.rx) - first
        subprocess.run(["callgrind_control", "-d", str(node.proc.pid)], check=True,
                       stdout=subprocess.DEVNULL)
        subprocess.run(["callgrind_control", "-i", "off", str(node.proc.pid)], check=True,
                       stdout=subprocess.DEVNULL)
    finally:
        node.stop()
        sim.stop()
    # The dump of the window: one file per thread (PID.N-TT; the final dump at exit, which
    # collected nothing more, has no number); the bus thread's is the one spending most in the
    # scheduler and the link.
    files = [f for f in glob.glob(out + ".*") if re.search(r"\.\d+-\d+$", f)]
    dumped = sorted({re.search(r"\.(\d+)-\d+$", f).group(1) for f in files}, key=int)
    files = [f for f in files if re.search(r"\.%s-\d+$" % dumped[0], f)] if dumped else []
    everything, bus, bus_functions, bus_file = 0, 0, {}, None
    for f in files:
        total, functions = thread_costs(f)
        everything += total
        marked = sum(v for k, v in functions.items() if any(m in k for m in BUS_MARKERS))
        if marked and total > bus:
            bus, bus_functions, bus_file = total, functions, f
    allocated = allocations(bus_file) if bus_file else (0, {})
    return transactions, everything, bus, bus_functions, allocated


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="the counted window")
    parser.add_argument("--warmup", type=float, default=10.0)
    parser.add_argument("--node", action="append", default=[],
                        help="another build's modbus_rtu_bus, measured too")
    parser.add_argument("--keep", help="leave each build's callgrind files in a folder here")
    args = parser.parse_args()
    if not shutil.which("valgrind") or not shutil.which("callgrind_annotate"):
        print("callgrind_node.py: needs valgrind (apt-get install valgrind)", file=sys.stderr)
        return 2
    builds = [("this build", None)] + [(exe, exe) for exe in args.node]
    rows = []
    with node_bench.own_master("modbus_rtu_callgrind_node"):
        for name, exe in builds:
            for only, what in DEVICES:
                with tempfile.TemporaryDirectory() as workdir:
                    if args.keep:
                        workdir = tempfile.mkdtemp(prefix="callgrind_node_", dir=args.keep)
                    rows.append((name, what) + measure(workdir, exe, args.seconds, args.warmup,
                                                       only))
    print("## Instructions per transaction (callgrind, %.0f s window, each device polled at "
          "50 Hz, 115200)\n" % args.seconds)
    print("| build | devices polled | transactions | bus thread [instructions/transaction] | "
          "whole node [instructions/transaction] | bus thread [allocations/transaction] |")
    print("|---|---|---|---|---|---|")
    for name, what, n, everything, bus, _, (allocs, _) in rows:
        print("| %s | %s | %d | %.0f | %.0f | %.1f |" % (name, what, n, bus / max(n, 1),
                                                        everything / max(n, 1), allocs / max(n, 1)))
    for name, what, n, _, bus, functions, (allocs, callers) in rows:
        print("\n| %s, %s: the bus thread's top 10 functions (self) | instructions/transaction | "
              "of the thread [%%] |\n|---|---|---|" % (name, what))
        for fn, ir in sorted(functions.items(), key=lambda kv: -kv[1])[:10]:
            print("| `%s` | %.0f | %.1f |" % (fn[:90], ir / max(n, 1), 100.0 * ir / max(bus, 1)))
        print("\n| %s, %s: who allocates on the bus thread (the package's functions above "
              "each allocation) | "
              "allocations/transaction |\n|---|---|" % (name, what))
        for fn, calls in sorted(callers.items(), key=lambda kv: -kv[1])[:15]:
            print("| `%s` | %.2f |" % (fn[:110], calls / max(n, 1)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
