#!/usr/bin/env python3
"""Runs one rostest with what it needs from the machine chosen when it runs, so that a second
run of the suite, or a node sharing on 1502 beside it, cannot clash with it:

- every required launch arg named `dir` (one with neither `default` nor `value`) gets a new
  folder under $TMPDIR, removed afterwards (ptys, control sockets and reports live there);
- every required launch arg whose name ends in `_port` gets a TCP port that is free on
  127.0.0.1 now (the kernel picks it: bind to port 0).

rostest's own master already takes a free port. The test command runs every rostest through
this (test/CMakeLists.txt); by hand:

    test/run_rostest.py test/rostest/share.test [rostest options]
"""
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET


def required_args(test_file):
    """Names of the launch file's top-level args that have neither default nor value."""
    root = ET.parse(test_file).getroot()
    return [a.get("name") for a in root.findall("arg")
            if a.get("default") is None and a.get("value") is None]


def free_ports(count):
    """`count` distinct TCP ports free on 127.0.0.1, all held until all are chosen."""
    sockets = []
    try:
        for _ in range(count):
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.bind(("127.0.0.1", 0))
            sockets.append(s)
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def launch_args(test_file, make_dir=tempfile.mkdtemp, pick_ports=free_ports):
    """The `name:=value` arguments for the test file's required args, and the folders made."""
    names = required_args(test_file)
    unknown = [n for n in names if n != "dir" and not n.endswith("_port")]
    if unknown:
        raise SystemExit(f"{test_file}: required arg(s) {', '.join(unknown)}: run_rostest.py "
                         "fills only 'dir' and '*_port'; give the others a default")
    port_names = [n for n in names if n.endswith("_port")]
    values, folders = {}, []
    stem = os.path.splitext(os.path.basename(test_file))[0]
    for name in names:
        if name == "dir":
            folders.append(make_dir(prefix=f"modbus_rtu_rostest_{stem}_"))
            values[name] = folders[-1]
    values.update(zip(port_names, pick_ports(len(port_names))))
    return [f"{k}:={v}" for k, v in values.items()], folders


def main(argv):
    test_files = [a for a in argv if a.endswith(".test")]
    if len(test_files) != 1:
        print("usage: run_rostest.py [rostest options] FILE.test", file=sys.stderr)
        return 2
    extra, folders = launch_args(test_files[0])
    print(f"run_rostest.py: {os.path.basename(test_files[0])} {' '.join(extra)}", flush=True)
    rostest = shutil.which("rostest") or "/usr/bin/rostest"
    try:
        return subprocess.call([sys.executable, rostest] + argv + extra)
    finally:
        for f in folders:
            shutil.rmtree(f, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
