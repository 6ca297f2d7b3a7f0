// RtuOverTcpLink against a real socket: byte-exact RTU frames, the serial rules on the far side
// (stale bytes dropped, reply read by length, CRC checked, addresses 0 and 248-255), lost
// replies, a dropped connection and the reconnect.
#include <gtest/gtest.h>

#include "modbus_rtu_driver/core/link/make_link.h"
#include "modbus_rtu_driver/core/link/modbus_tcp_link.h"
#include "modbus_rtu_driver/core/link/rtu_link.h"
#include "modbus_rtu_driver/core/link/rtu_over_tcp_link.h"
#include "tcp_test_server.h"
#include "wait_for.h"

namespace modbus_rtu_driver {
namespace {

LinkConfig gateway(int port) {
  LinkConfig c = testTcpLinkConfig(TcpFraming::kRtu, port);
  c.late_reply_guard = 0;
  return c;
}

// Answers every request as a device would, with `reply_of(request)`, until the client closes.
TestTcpServer::Serve answeringAsADevice(const std::function<Bytes(const Request&)>& reply_of) {
  return answering([reply_of](const Bytes& frame) {
    const auto request = decodeRequest(frame);
    return request ? reply_of(*request) : Bytes{};
  });
}

Bytes holdingReply(const Request& r) {
  return encodeReply(r, std::vector<uint16_t>(r.count, 0x1234));
}

TEST(RtuOverTcpLink, FactoryChoosesByPortForm) {
  LinkConfig c;
  c.port = "rtu+tcp://gw:502";
  EXPECT_NE(dynamic_cast<RtuOverTcpLink*>(makeLink(c).get()), nullptr);
  EXPECT_STREQ(makeLink(c)->target().type->name, "RTU over TCP");
  c.port = "tcp://gw:502";
  EXPECT_NE(dynamic_cast<ModbusTcpLink*>(makeLink(c).get()), nullptr);
  EXPECT_STREQ(makeLink(c)->target().type->name, "Modbus TCP");
  c.port = "/dev/ttyUSB0";
  EXPECT_NE(dynamic_cast<RtuLink*>(makeLink(c).get()), nullptr);
  EXPECT_STREQ(makeLink(c)->target().type->name, "serial RTU");
}

TEST(RtuOverTcpLink, SendsTheRtuFrameByteForByteAndReadsTheReply) {
  TestTcpServer s(TcpFraming::kRtu, answeringAsADevice(holdingReply));
  RtuOverTcpLink link(gateway(s.port()));
  std::string error;
  ASSERT_TRUE(link.connect(&error)) << error;
  const Result r = link.execute(Request::readHoldingRegisters(1, 0x00FD, 1));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, std::vector<uint16_t>{0x1234});
  ASSERT_EQ(s.received().size(), 1u);
  EXPECT_EQ(toHex(s.received()[0]), "01 03 00 FD 00 01 15 FA");
}

TEST(RtuOverTcpLink, ReachesAddressesLibmodbusCannotAndBroadcasts) {
  TestTcpServer s(TcpFraming::kRtu, answeringAsADevice(holdingReply));
  RtuOverTcpLink link(gateway(s.port()));
  ASSERT_TRUE(link.connect(nullptr));
  EXPECT_TRUE(link.execute(Request::readHoldingRegisters(255, 2, 2)).ok());
  EXPECT_TRUE(link.execute(Request::readHoldingRegisters(248, 2, 2)).ok());
  // A broadcast is sent and not waited for (the server's reply, if any, is dropped as stale).
  EXPECT_TRUE(link.execute(Request::writeSingleRegister(0, 3, 7)).ok());
  ASSERT_TRUE(waitFor([&] { return s.received().size() == 3; }));
  EXPECT_EQ(s.received()[0][0], 255);
  EXPECT_EQ(s.received()[1][0], 248);
  EXPECT_EQ(toHex(s.received()[2]), toHex(encodeRequest(Request::writeSingleRegister(0, 3, 7))));
  EXPECT_EQ(link.stats().broadcasts, 1u);
}

TEST(RtuOverTcpLink, ThrowsAwayStaleBytesBeforeARequest) {
  // Noise right behind the first reply, in the same segment: it waits in the socket.
  TestTcpServer s(TcpFraming::kRtu, answeringAsADevice([](const Request& r) {
                    Bytes reply = holdingReply(r);
                    if (r.address == 1)
                      for (uint8_t b : {0x00, 0xFF, 0x55, 0x03, 0x13}) reply.push_back(b);
                    return reply;
                  }));
  RtuOverTcpLink link(gateway(s.port()));
  ASSERT_TRUE(link.connect(nullptr));
  ASSERT_TRUE(link.execute(Request::readHoldingRegisters(1, 1, 1)).ok());
  const Result r = link.execute(Request::readHoldingRegisters(1, 2, 1));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(link.stats().stale_bytes, 5u);
}

TEST(RtuOverTcpLink, BadCrcIsALostAnswerAndRetried) {
  int replies = 0;
  TestTcpServer s(TcpFraming::kRtu, answeringAsADevice([&](const Request& r) {
                    Bytes reply = holdingReply(r);
                    if (replies++ == 0) reply.back() ^= 0xA5;
                    return reply;
                  }));
  RtuOverTcpLink link(gateway(s.port()));
  ASSERT_TRUE(link.connect(nullptr));
  const Result r = link.execute(Request::readHoldingRegisters(1, 0, 1));
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(link.stats().crc_errors, 1u);
  EXPECT_EQ(link.stats().retries, 1u);
}

TEST(RtuOverTcpLink, LostReplyTimesOutAndANonRepeatableWriteIsSentOnce) {
  TestTcpServer s(TcpFraming::kRtu, hearingOnly());
  RtuOverTcpLink link(gateway(s.port()));
  ASSERT_TRUE(link.connect(nullptr));
  Request once = Request::writeSingleCoil(1, 0, true);
  once.repeatable = false;
  const Result r = link.execute(once);
  EXPECT_EQ(r.error, ErrorKind::kTimeout);
  EXPECT_TRUE(answerLost(r.error));  // so the device reads back before reporting it failed
  EXPECT_EQ(link.execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kTimeout);
  ASSERT_TRUE(waitFor([&] { return s.received().size() == 3; }));
  EXPECT_EQ(s.received()[0], encodeRequest(once));  // once, then the read and its retry
  EXPECT_EQ(s.received()[1], s.received()[2]);
  EXPECT_TRUE(link.connected());
}

TEST(RtuOverTcpLink, DroppedConnectionIsAnIoErrorNotResentThenReconnects) {
  // The first connection dies mid-request (a gateway reboot); later ones answer.
  TestTcpServer s(TcpFraming::kRtu, droppingTheFirstConnection(answeringAsADevice(
                                        [](const Request& r) { return encodeReply(r, {1}); })));
  RtuOverTcpLink link(gateway(s.port()));
  ASSERT_TRUE(link.connect(nullptr));
  const Result r = link.execute(Request::writeSingleCoil(1, 0, true));
  EXPECT_EQ(r.error, ErrorKind::kIo) << r.message;
  EXPECT_FALSE(link.connected());
  EXPECT_EQ(s.received().size(), 1u);  // not resent: it may have been carried out
  EXPECT_EQ(link.execute(Request::readCoils(1, 0, 1)).error, ErrorKind::kNotConnected);
  std::string error;
  ASSERT_TRUE(link.connect(&error)) << error;
  const Result again = link.execute(Request::writeSingleCoil(1, 0, true));
  EXPECT_TRUE(again.ok()) << again.message;
  EXPECT_EQ(link.stats().reconnects, 1u);
  EXPECT_EQ(link.stats().io_errors, 1u);
}

TEST(RtuOverTcpLink, ConnectToNothingSaysWhere) {
  int port = 0;
  {
    TestTcpServer gone(TcpFraming::kRtu, hearingOnly());
    port = gone.port();
  }
  RtuOverTcpLink link(gateway(port));
  std::string error;
  EXPECT_FALSE(link.connect(&error));
  EXPECT_NE(error.find("127.0.0.1:" + std::to_string(port)), std::string::npos) << error;
}

TEST(RtuOverTcpLink, TimeoutIsTheWireTimePlusTheNetworkAllowance) {
  LinkConfig c = gateway(1);
  c.baud = 9600;
  c.network_allowance = 0.25;
  // 8-byte request, 7-byte reply: (8 + 7) characters of 10 bits, t3.5, turnaround, allowance
  const double expected = 15 * 10.0 / 9600 + 3.5 * 10.0 / 9600 + kTurnaroundAllowance + 0.25;
  EXPECT_NEAR(gatewayResponseTimeout(c, 8, 7), expected, 1e-9);
}

}  // namespace
}  // namespace modbus_rtu_driver
