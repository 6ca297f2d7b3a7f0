"""A tiny Modbus TCP client of the node's share (standard library only): FC01 and FC05, and a
burst of FC05 requests sent without waiting for the replies (to queue them in the node)."""
import socket
import struct


class ShareError(RuntimeError):
    """The share answered with a Modbus exception (code) or not at all (code None)."""

    def __init__(self, code, text):
        super().__init__(text)
        self.code = code


class ShareClient:
    def __init__(self, port, unit, timeout=5.0):
        self.port, self.unit, self.timeout = port, unit, timeout
        self.tid = 0

    def _frame(self, pdu):
        self.tid = (self.tid + 1) & 0xFFFF
        return struct.pack(">HHHB", self.tid, 0, len(pdu) + 1, self.unit) + pdu

    @staticmethod
    def _recv_exact(s, n):
        data = b""
        while len(data) < n:
            chunk = s.recv(n - len(data))
            if not chunk:
                raise ShareError(None, "share closed the connection")
            data += chunk
        return data

    def _reply(self, s):
        header = self._recv_exact(s, 7)
        _, _, length, _ = struct.unpack(">HHHB", header)
        pdu = self._recv_exact(s, length - 1)
        if pdu[0] & 0x80:
            raise ShareError(pdu[1], "exception %02X to FC%02d" % (pdu[1], pdu[0] & 0x7F))
        return pdu

    def _transact(self, pdu):
        try:
            with socket.create_connection(("127.0.0.1", self.port), timeout=self.timeout) as s:
                s.sendall(self._frame(pdu))
                return self._reply(s)
        except socket.timeout:
            raise ShareError(None, "no reply from the share within %.1f s" % self.timeout)

    def read_coils(self, address, count):
        pdu = self._transact(struct.pack(">BHH", 1, address, count))
        bits = int.from_bytes(pdu[2:2 + pdu[1]], "little")
        return [(bits >> i) & 1 for i in range(count)]

    def write_coil(self, address, on):
        self._transact(struct.pack(">BHH", 5, address, 0xFF00 if on else 0))

    def burst_write_coil(self, address, on, count):
        """Sends `count` FC05 requests, each on its own connection, without reading replies;
        returns the open sockets (the caller closes them) so the node keeps them queued."""
        sockets = []
        for _ in range(count):
            s = socket.create_connection(("127.0.0.1", self.port), timeout=self.timeout)
            s.sendall(self._frame(struct.pack(">BHH", 5, address, 0xFF00 if on else 0)))
            sockets.append(s)
        return sockets
