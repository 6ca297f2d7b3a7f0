"""The project's one Modbus TCP client for its own tests, benchmark and soak (standard library
only: the same on Debian 11's Python 3.9 and Debian 13's 3.13).

It gives what those checks need and a library client hides: the transaction id of every
answer (an answer to an earlier request is out of step, not the reply), several requests sent
before their answers are read (to queue them in the node), exception answers as values, and a
deadline per answer. The independent clients (mbpoll, pymodbus) stay in the tests that check the
share against them (test_share.py, test_modbus_tcp_node.py).

    with MbapClient(port, unit=8) as c:
        c.read_coils(0, 8)          # [0, 1, ...]; ModbusError on an exception answer
        c.write_coil(3, True)       # the echo checked
        c.request(pdu)              # the answer's PDU as it came (an exception too)
"""
import socket
import struct
import time


class ModbusError(RuntimeError):
    """An exception answer (`code`), or none: no answer in time, or the server closed the
    connection (`closed`), with `code` None."""

    def __init__(self, code, text, closed=False):
        super().__init__(text)
        self.code, self.closed = code, closed


def read_pdu(address, count, function=1):
    """FC01-FC04: `count` items from `address`."""
    return struct.pack(">BHH", function, address, count)


def write_coil_pdu(address, on):
    """FC05: the whole request comes back as the answer."""
    return struct.pack(">BHH", 5, address, 0xFF00 if on else 0)


def write_registers_pdu(address, values):
    """FC16: the answer echoes the address and the count."""
    return (struct.pack(">BHHB", 16, address, len(values), 2 * len(values)) +
            b"".join(struct.pack(">H", v) for v in values))


class MbapClient:
    """One TCP connection to a Modbus TCP server; requests carry increasing transaction ids."""

    def __init__(self, port, unit, host="127.0.0.1", timeout=5.0, first_tid=1):
        self.unit, self.timeout = unit, timeout
        self.tid = (first_tid - 1) & 0xFFFF
        self.buffer = b""  # bytes of answers not yet taken (a late answer stays here)
        # A server that does not listen raises OSError here: not an answer, a broken set-up.
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        self.sock.close()

    def send(self, pdu, unit=None):
        """Sends one request; returns its transaction id (the answer is not read)."""
        self.tid = (self.tid + 1) & 0xFFFF
        unit = self.unit if unit is None else unit
        self.sock.sendall(struct.pack(">HHHB", self.tid, 0, len(pdu) + 1, unit) + pdu)
        return self.tid

    def receive(self, timeout=None):
        """The next whole answer as (transaction id, unit, PDU), within `timeout` s (the
        client's when None). ModbusError(None) when none came in time or the server closed."""
        wait = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + wait
        while len(self.buffer) < 6 or len(self.buffer) < 6 + struct.unpack(">H",
                                                                         self.buffer[4:6])[0]:
            left = deadline - time.monotonic()
            if left <= 0:
                raise ModbusError(None, "no answer within %.3f s" % wait)
            self.sock.settimeout(left)
            try:
                chunk = self.sock.recv(260)
            except socket.timeout:
                continue  # the deadline above decides
            if not chunk:
                raise ModbusError(None, "the server closed the connection", closed=True)
            self.buffer += chunk
        length = 6 + struct.unpack(">H", self.buffer[4:6])[0]
        frame, self.buffer = self.buffer[:length], self.buffer[length:]
        tid, _, _, unit = struct.unpack(">HHHB", frame[:7])
        return tid, unit, frame[7:]

    def request(self, pdu, unit=None):
        """One request and its answer's PDU as it came (an exception answer too). An answer
        with another transaction id raises: the connection is out of step."""
        tid = self.send(pdu, unit)
        got, _, answer = self.receive()
        if got != tid:
            raise ModbusError(None, "out of step: transaction %d answered %d" % (tid, got))
        return answer

    def transact(self, pdu, unit=None):
        """request(), with an exception answer raised as ModbusError(code)."""
        answer = self.request(pdu, unit)
        if answer[0] & 0x80:
            raise ModbusError(answer[1], "exception %02X to FC%02d" % (answer[1], answer[0] & 0x7F))
        return answer

    def read_bits(self, address, count, function=1):
        answer = self.transact(read_pdu(address, count, function))
        bits = int.from_bytes(answer[2:2 + answer[1]], "little")
        return [(bits >> i) & 1 for i in range(count)]

    def read_coils(self, address, count):
        return self.read_bits(address, count, 1)

    def read_registers(self, address, count, function=3):
        answer = self.transact(read_pdu(address, count, function))
        return list(struct.unpack(">%dH" % count, answer[2:2 + 2 * count]))

    def write_coil(self, address, on):
        self.expect_echo(write_coil_pdu(address, on), 5)

    def write_registers(self, address, values):
        self.expect_echo(write_registers_pdu(address, values), 5)

    def expect_echo(self, pdu, echoed):
        """A write whose answer repeats the request's first `echoed` PDU bytes."""
        answer = self.transact(pdu)
        if answer[:echoed] != pdu[:echoed]:
            raise ModbusError(None, "unexpected answer %s to %s" % (answer.hex(), pdu.hex()))


def write_outcome(port, unit, pdu, echoed, timeout=10.0):
    """A write on a connection of its own, as a word: "ok" when the answer echoes the request's
    first `echoed` PDU bytes, "exception N" on an exception answer, else "unexpected ..."."""
    with MbapClient(port, unit, timeout=timeout) as c:
        try:
            c.expect_echo(pdu, echoed)
        except ModbusError as e:
            return "exception %d" % e.code if e.code is not None else "unexpected: %s" % e
    return "ok"
