#!/usr/bin/env python3
"""Client of the simulator's control socket (standard library only).

    python3 test/sim_control.py SOCKET get 255 coil 0 8
    python3 test/sim_control.py SOCKET set 255 input 1 1
    python3 test/sim_control.py SOCKET power_cycle

Devices are named by current address or by index (#0, #1, ...); tables: coil, input, holding,
ireg."""
import socket
import sys


class SimError(RuntimeError):
    pass


class SimControl:
    def __init__(self, path, timeout=5.0):
        self.path = path
        self.timeout = timeout

    def command(self, line):
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(self.timeout)
            s.connect(self.path)
            s.sendall((line + "\n").encode())
            reply = b""
            while not reply.endswith(b"\n"):
                chunk = s.recv(4096)
                if not chunk:
                    break
                reply += chunk
        text = reply.decode().strip()
        if not text.startswith("ok"):
            raise SimError("%s -> %s" % (line, text))
        return text[2:].split()

    def get(self, device, table, address, count=1):
        return [int(v) for v in self.command("get %s %s %d %d" % (device, table, address, count))]

    def set(self, device, table, address, *values):
        self.command("set %s %s %d %s" % (device, table, address, " ".join(str(v) for v in values)))

    def power_cycle(self):
        self.command("power_cycle")

    def silence(self, device, on=True):
        self.command("silence %s %d" % (device, 1 if on else 0))

    def fail(self, device, on=True):
        """The device answers every request with exception 04 (slave device failure)."""
        self.command("fail %s %d" % (device, 1 if on else 0))

    def corrupt(self, device, replies=1):
        """The next `replies` replies of the device carry a bad CRC."""
        self.command("corrupt %s %d" % (device, replies))

    def info(self):
        """[(index, type, address, baud, parity)]"""
        out = []
        for item in self.command("info"):
            index, dtype, address, baud, parity = item.split(":")
            out.append((int(index[1:]), dtype, int(address), int(baud), parity))
        return out

    def frames(self):
        """(frames received, frames answered, frames dropped for a bad CRC)"""
        return tuple(int(v) for v in self.command("frames"))


if __name__ == "__main__":
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(2)
    try:
        print(" ".join(SimControl(sys.argv[1]).command(" ".join(sys.argv[2:]))))
    except SimError as e:
        print(e, file=sys.stderr)
        sys.exit(1)
