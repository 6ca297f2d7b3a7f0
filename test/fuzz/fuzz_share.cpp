// libFuzzer target: arbitrary bytes from a Modbus TCP client at the share (a ShareGateway on a
// real loopback socket, a real BusScheduler over in-memory devices). Invariants: nothing
// crashes (ASan/UBSan watch), every reply answers a frame that was sent (its transaction id
// and unit, the same function or its exception), the server closes the connection once the
// client has finished, and every 500 inputs a valid request on a new connection still gets its
// true answer.
#include <cstdio>
#include <cstdlib>

#include "share_test_bus.h"

using namespace modbus_rtu_driver;

namespace {

// Aborts (libFuzzer keeps the input) and says which invariant broke.
#define check(ok) checkAt((ok), #ok, __LINE__)
void checkAt(bool ok, const char* what, int line) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_share.cpp:%d: invariant broken: %s\n", line, what);
  std::abort();
}

ShareFixture& share() {
  static ShareFixture* fixture = [] {
    ShareConfig config;
    config.server.max_clients = 2;
    auto* f = new ShareFixture(config);  // lives for the whole run
    check(f->start());
    return f;
  }();
  return *fixture;
}

void checkStillAnswers(uint16_t port, uint16_t value) {
  TcpClient c(port);
  check(c.connected());
  const Request write = Request::writeSingleRegister(1, 200, value);
  check(c.send(0xABCD, write));
  check(c.receive(5.0) == rtuToMbap(0xABCD, encodeReply(write, {})));
  const Request read = Request::readHoldingRegisters(1, 200, 1);
  check(c.send(0xABCE, read));
  check(c.receive(5.0) == rtuToMbap(0xABCE, encodeReply(read, {value})));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static unsigned inputs = 0;
  ShareFixture& f = share();
  const Bytes input(data, data + size);
  std::vector<Bytes> unanswered = mbapFramesIn(input);
  {
    TcpClient c(f.port());
    check(c.connected());
    if (!input.empty()) check(c.sendBytes(input));
    shutdown(c.fd(), SHUT_WR);  // finished: the server must close, whatever it got
    for (Bytes reply; !(reply = c.receive(5.0)).empty();)
      check(reply.size() >= 9 && takeAnswered(&unanswered, reply));
    check(c.closedByServer(5.0));
  }
  if (++inputs % 500 == 0) checkStillAnswers(f.port(), static_cast<uint16_t>(inputs));
  return 0;
}
