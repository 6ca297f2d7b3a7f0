#!/usr/bin/env python3
"""Client of modbus_rtu_simulator's control socket (Python 3 standard library only).

    python3 test/sim_control.py SOCKET get '#0' coil 0 8       -> ok 0 0 1 0 0 0 0 0
    python3 test/sim_control.py SOCKET set 255 discrete_input 1 1       -> ok
    python3 test/sim_control.py SOCKET power_cycle 255         -> ok

The socket is the simulator's --control path (default: the link path + ".ctl"). One command per
line, one reply line each: "ok ..." or "error <message>". The command line prints the answer as
the simulator sent it: "ok ..." on stdout (exit 0), or the command and the error on stderr
(exit 1).

Devices: "#<index>" in config order, or the current address (decimal or 0x hex).
Tables: coil, discrete_input, holding_register, input_register.
Commands:
    get DEV TABLE ADDR [COUNT]       values
    set DEV TABLE ADDR V1 [V2 ...]   coil/holding_register: one bus write with the device's
                                     checks; discrete_input/input_register: state from
                                     outside (-32768..65535)
    silence DEV 0|1                  the device hears and answers nothing (unplugged)
    fail DEV 0|1                     the device answers everything with exception 04
    corrupt DEV N                    the next N replies of the device carry a bad CRC
    truncate DEV N                   the next N replies are cut to half their length
    wrong_address DEV N              the next N replies name another slave (valid CRC)
    noise DEV N                      the next N replies are followed by 5 noise bytes
    late DEV N MS                    the next N replies are sent MS milliseconds late
    drop DEV PERCENT request|reply   lose that share of requests (nothing done) or replies
    stats DEV                        changes N dropped_requests N dropped_replies N
    power_cycle [DEV]                every device (or only DEV) off and on
    info                             #INDEX:TYPE:ADDRESS:BAUD:PARITY per device
    frames                           frames received, replies sent, byte runs dropped
    gateway                          port P connections N accepted N dropped N (--rtu-tcp)
    gateway_drop [MS]                the RTU-over-TCP gateway drops its connections; with MS
                                     it refuses new ones for MS ms (a reboot)
    help
"""
import socket
import sys


class SimError(RuntimeError):
    pass


class SimControl:
    def __init__(self, path, timeout=5.0):
        self.path = path
        self.timeout = timeout

    def command(self, line):
        """Sends one command; returns the words after "ok", raises SimError on "error"."""
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
        if text != "ok" and not text.startswith("ok "):
            raise SimError("%s -> %s" % (line, text))
        return text[2:].split()

    def get(self, device, table, address, count=1):
        return [int(v) for v in self.command("get %s %s %d %d" % (device, table, address, count))]

    def set(self, device, table, address, *values):
        if not values:
            raise ValueError("set needs at least one value")
        self.command("set %s %s %d %s" % (device, table, address, " ".join(str(v) for v in values)))

    def power_cycle(self, device=None):
        """Every device off and on, or only `device` (its own supply)."""
        self.command("power_cycle" + ("" if device is None else " %s" % device))

    def silence(self, device, on=True):
        self.command("silence %s %d" % (device, 1 if on else 0))

    def fail(self, device, on=True):
        """The device answers every request with exception 04 (slave device failure)."""
        self.command("fail %s %d" % (device, 1 if on else 0))

    def corrupt(self, device, replies=1):
        """The next `replies` replies of the device carry a bad CRC."""
        self.command("corrupt %s %d" % (device, replies))

    def spoil(self, kind, device, replies=1, late_ms=0):
        """The next `replies` replies of the device are spoilt: kind is corrupt, truncate,
        wrong_address, noise or late (sent `late_ms` late)."""
        extra = " %d" % late_ms if kind == "late" else ""
        self.command("%s %s %d%s" % (kind, device, replies, extra))

    def drop(self, device, percent, what):
        """Lose `percent` % of the device's requests (what="request": nothing is done) or of
        its replies (what="reply": done, the reply lost)."""
        self.command("drop %s %d %s" % (device, percent, what))

    def stats(self, device):
        """{"changes": N, "dropped_requests": N, "dropped_replies": N}"""
        words = self.command("stats %s" % device)
        return {words[i]: int(words[i + 1]) for i in range(0, len(words), 2)}

    def info(self):
        """[(index, type, address, baud, parity)]"""
        out = []
        for item in self.command("info"):
            index, dtype, address, baud, parity = item.split(":")
            out.append((int(index[1:]), dtype, int(address), int(baud), parity))
        return out

    def frames(self):
        """(frames received, replies sent, runs of bytes dropped: bad CRC or noise)"""
        return tuple(int(v) for v in self.command("frames"))


def main(argv):
    if len(argv) < 3 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 2
    try:
        print(" ".join(["ok"] + SimControl(argv[1]).command(" ".join(argv[2:]))))
    except SimError as e:
        print(e, file=sys.stderr)
        return 1
    except OSError as e:
        print("%s: %s" % (argv[1], e), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
