// The share fuzzed with malformed Modbus TCP input (a fixed seed, so a failure can be
// repeated): random bytes, random PDUs behind valid headers, valid requests with a byte
// changed, cut short or followed by junk. The invariant: the server never crashes; on each
// connection it answers only frames that were sent (their transaction id and unit, the same
// function or its exception) and closes the connection once the client has finished
// (half-close) or sent a header that is not Modbus TCP; afterwards a valid request on a new
// connection still gets its true answer.
#include <gtest/gtest.h>

#include <random>

#include "share_test_bus.h"

using namespace modbus_rtu_driver;

namespace {

Bytes randomBytes(std::mt19937& rng, size_t n) {
  Bytes b(n);
  for (auto& x : b) x = static_cast<uint8_t>(rng());
  return b;
}

Bytes validRequest(std::mt19937& rng) {
  const uint8_t unit = std::vector<uint8_t>{0, 1, 1, 1, 5, 9}[rng() % 6];
  const uint16_t address = static_cast<uint16_t>(rng() % 120);
  Request r;
  switch (rng() % 6) {
    case 0:
      r = Request::readHoldingRegisters(unit == 0 ? 1 : unit, address, 1 + rng() % 8);
      break;
    case 1:
      r = Request::readCoils(unit == 0 ? 1 : unit, address, 1 + rng() % 20);
      break;
    case 2:
      r = Request::writeSingleRegister(unit, address, static_cast<uint16_t>(rng()));
      break;
    case 3:
      r = Request::writeSingleCoil(unit, address, rng() % 2);
      break;
    case 4:
      r = Request::writeMultipleRegisters(unit, address, {1, 2, 3});
      break;
    default:
      r = Request::writeMultipleCoils(unit, address, {true, false, true});
  }
  return rtuToMbap(static_cast<uint16_t>(rng()), encodeRequest(r));
}

Bytes malformedInput(std::mt19937& rng) {
  Bytes in;
  switch (rng() % 5) {
    case 0:  // noise
      return randomBytes(rng, 1 + rng() % 300);
    case 1: {  // a valid header, a random PDU
      const size_t length = 2 + rng() % 253;
      in = {static_cast<uint8_t>(rng()),       static_cast<uint8_t>(rng()), 0, 0,
            static_cast<uint8_t>(length >> 8), static_cast<uint8_t>(length)};
      const Bytes body = randomBytes(rng, length);
      in.insert(in.end(), body.begin(), body.end());
      return in;
    }
    case 2:  // a valid request with one byte changed
      in = validRequest(rng);
      in[rng() % in.size()] ^= static_cast<uint8_t>(1 + rng() % 255);
      return in;
    case 3:  // cut short
      in = validRequest(rng);
      in.resize(1 + rng() % (in.size() - 1));
      return in;
    default: {  // several valid requests, then junk
      for (int i = 0; i < 3; ++i) {
        const Bytes one = validRequest(rng);
        in.insert(in.end(), one.begin(), one.end());
      }
      const Bytes junk = randomBytes(rng, rng() % 20);
      in.insert(in.end(), junk.begin(), junk.end());
      return in;
    }
  }
}

}  // namespace

TEST(ShareFuzz, MalformedInputNeverBreaksTheServer) {
  ShareConfig config;
  config.server.max_clients = 2;
  ShareFixture f(config);
  ASSERT_TRUE(f.start());
  std::mt19937 rng(20261201);
  constexpr int kRounds = 2000;
  int answered = 0;
  for (int round = 0; round < kRounds; ++round) {
    const Bytes input = malformedInput(rng);
    const std::vector<Bytes> sent = mbapFramesIn(input);
    TcpClient c(f.port());
    ASSERT_TRUE(c.connected()) << "round " << round;
    c.sendBytes(input);
    shutdown(c.fd(), SHUT_WR);  // finished: the server must close, whatever it got
    // Each reply answers one frame sent, not yet answered (the server's own refusals may come
    // before the answers from the bus).
    std::vector<Bytes> unanswered = sent;
    for (;;) {
      const Bytes reply = c.receive();
      if (reply.empty()) break;
      ASSERT_GE(reply.size(), 9u) << "round " << round << ": " << toHex(reply);
      ASSERT_TRUE(takeAnswered(&unanswered, reply))
          << "round " << round << ": reply " << toHex(reply) << " to nothing sent";
      ++answered;
    }
    ASSERT_TRUE(c.closedByServer()) << "round " << round << ": not closed after " << toHex(input);
  }
  EXPECT_GT(answered, kRounds / 4);  // the inputs did reach the request handling
  // The server is intact: a valid request on a new connection gets its true answer.
  TcpClient c(f.port());
  const Request write = Request::writeSingleRegister(1, 200, 0x4242);
  ASSERT_TRUE(c.send(0xABCD, write));
  EXPECT_EQ(c.receive(), rtuToMbap(0xABCD, encodeReply(write, {})));
  const Request read = Request::readHoldingRegisters(1, 200, 1);
  ASSERT_TRUE(c.send(0xABCE, read));
  EXPECT_EQ(c.receive(), rtuToMbap(0xABCE, encodeReply(read, {0x4242})));
}
