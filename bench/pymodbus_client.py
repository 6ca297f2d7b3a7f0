#!/usr/bin/env python3
"""The pymodbus column of the benchmark: Debian's python3-pymodbus (synchronous serial client,
RTU framer) against the simulator at PORT, slave SLAVE, SECONDS per function. Prints one line
per function: "<code> <transactions per second>" (0 when a transaction failed).

    pymodbus_client.py PORT SLAVE SECONDS
"""
import logging
import sys
import time

from pymodbus.client import ModbusSerialClient


def main(port, slave, seconds):
    logging.disable(logging.CRITICAL)  # pymodbus logs every retry at warning level
    client = ModbusSerialClient(port, baudrate=115200, timeout=0.5, retries=0)
    if not client.connect():
        print("cannot open %s" % port, file=sys.stderr)
        return 1
    # pymodbus 3.0.0 (Debian 12) loses the timeout on the way to pyserial (params.timeout and
    # socket.timeout read 0), so every read polls once and gives up before the reply is there.
    client.socket.timeout = 0.5
    calls = [
        ("01", lambda: client.read_coils(0, 8, slave=slave)),
        ("03", lambda: client.read_holding_registers(0, 3, slave=slave)),
        ("04", lambda: client.read_input_registers(0, 5, slave=slave)),
        ("05", lambda: client.write_coil(1, True, slave=slave)),
        ("15", lambda: client.write_coils(0, [False] * 8, slave=slave)),
        ("16", lambda: client.write_registers(0, [2500, 2000, 1600], slave=slave)),
    ]
    for code, call in calls:
        n, start = 0, time.monotonic()
        end = start + seconds
        ok = True
        while time.monotonic() < end:
            reply = call()
            if reply is None or reply.isError():
                ok = False
                break
            n += 1
        rate = n / (time.monotonic() - start) if ok else 0.0
        print("%s %.1f" % (code, rate), flush=True)
    client.close()
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1], int(sys.argv[2]), float(sys.argv[3])))
