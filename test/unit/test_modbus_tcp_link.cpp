// ModbusTcpLink against a real socket: byte-exact MBAP frames, unit ids 0-255, replies matched by
// transaction id, lost replies, a broken stream, a dropped connection and the reconnect.
#include <gtest/gtest.h>

#include <atomic>

#include "modbus_rtu_driver/core/link/modbus_tcp_link.h"
#include "tcp_test_server.h"
#include "wait_for.h"

namespace modbus_rtu_driver {
namespace {

LinkConfig server(int port) {
  return testTcpLinkConfig(TcpFraming::kMbap, port);
}

// The reply to the MBAP request `mbap`, as a Modbus TCP server sends it (same transaction id).
Bytes replyTo(const Bytes& mbap, const std::vector<uint16_t>& values) {
  const Request r = *decodeRequest(mbapToRtu(mbap));
  return rtuToMbap(mbapTransaction(mbap), encodeReply(r, values));
}

// Answers every request with the value 7.
TestTcpServer::Serve answeringSeven() {
  return answering([](const Bytes& f) { return replyTo(f, {7}); });
}

TEST(ModbusTcpLink, SendsTheMbapFrameByteForByteWithTheAddressAsUnitId) {
  TestTcpServer srv(TcpFraming::kMbap, answeringSeven());
  ModbusTcpLink link(server(srv.port()));
  ASSERT_TRUE(link.connect(nullptr));
  const Result r = link.execute(Request::readHoldingRegisters(1, 0x00FD, 1));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, std::vector<uint16_t>{7});
  EXPECT_TRUE(link.execute(Request::readHoldingRegisters(255, 0x00FD, 1)).ok());
  ASSERT_EQ(srv.received().size(), 2u);
  EXPECT_EQ(toHex(srv.received()[0]), "00 01 00 00 00 06 01 03 00 FD 00 01");
  EXPECT_EQ(toHex(srv.received()[1]), "00 02 00 00 00 06 FF 03 00 FD 00 01");
}

TEST(ModbusTcpLink, BroadcastGoesToUnitZeroAndIsNotWaitedFor) {
  TestTcpServer srv(TcpFraming::kMbap, hearingOnly());
  ModbusTcpLink link(server(srv.port()));
  ASSERT_TRUE(link.connect(nullptr));
  EXPECT_TRUE(link.execute(Request::writeSingleRegister(0, 3, 7)).ok());
  ASSERT_TRUE(waitFor([&] { return srv.received().size() == 1; }));
  EXPECT_EQ(toHex(srv.received()[0]), "00 01 00 00 00 06 00 06 00 03 00 07");
}

TEST(ModbusTcpLink, DropsRepliesWithAnotherTransactionId) {
  TestTcpServer srv(TcpFraming::kMbap, [](TestTcpServer& s, int fd) {
    for (Bytes f; !(f = s.readRequest(fd)).empty();) {
      Bytes stale = replyTo(f, {99});
      stale[1] ^= 0x40;  // an earlier transaction's late reply comes first
      TestTcpServer::write(fd, stale);
      if (mbapTransaction(f) == 1) TestTcpServer::write(fd, replyTo(f, {7}));
    }
  });
  LinkConfig c = server(srv.port());
  c.retries = 0;
  ModbusTcpLink link(c);
  ASSERT_TRUE(link.connect(nullptr));
  const Result r = link.execute(Request::readHoldingRegisters(1, 0, 1));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, std::vector<uint16_t>{7});
  // Only a wrong id: the answer is lost (timeout), never taken.
  const Result lost = link.execute(Request::readHoldingRegisters(1, 0, 1));
  EXPECT_EQ(lost.error, ErrorKind::kTimeout) << lost.message;
  EXPECT_EQ(link.stats().stale_bytes, 2 * 11u);
  EXPECT_TRUE(link.connected());
}

TEST(ModbusTcpLink, AReplyFromAnotherUnitIsAWrongAddress) {
  TestTcpServer srv(TcpFraming::kMbap, answering([](const Bytes& f) {
                      Bytes reply = replyTo(f, {7});
                      reply[6] = 9;
                      return reply;
                    }));
  ModbusTcpLink link(server(srv.port()));
  ASSERT_TRUE(link.connect(nullptr));
  EXPECT_EQ(link.execute(Request::readHoldingRegisters(1, 0, 1)).error, ErrorKind::kWrongAddress);
}

TEST(ModbusTcpLink, LostReplyOfANonRepeatableWriteIsNotResent) {
  TestTcpServer srv(TcpFraming::kMbap, hearingOnly());
  ModbusTcpLink link(server(srv.port()));
  ASSERT_TRUE(link.connect(nullptr));
  Request once = Request::writeSingleCoil(1, 0, true);
  once.repeatable = false;
  const Result r = link.execute(once);
  EXPECT_EQ(r.error, ErrorKind::kTimeout);
  EXPECT_TRUE(answerLost(r.error));
  EXPECT_EQ(link.execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kTimeout);
  ASSERT_TRUE(waitFor([&] { return srv.received().size() == 3; }));  // write once, read twice
  EXPECT_EQ(srv.received()[0][7], 0x05);
  EXPECT_EQ(srv.received()[1][7], 0x01);
  EXPECT_EQ(srv.received()[2][7], 0x01);
}

TEST(ModbusTcpLink, AStreamOutOfStepIsMalformedAndReconnects) {
  TestTcpServer srv(TcpFraming::kMbap, [](TestTcpServer& s, int fd) {
    for (Bytes f; !(f = s.readRequest(fd)).empty();) {
      Bytes reply = replyTo(f, {7});
      if (s.accepted() == 1) reply[3] = 1;  // protocol id 1: not Modbus
      TestTcpServer::write(fd, reply);
    }
  });
  ModbusTcpLink link(server(srv.port()));
  ASSERT_TRUE(link.connect(nullptr));
  const Result r = link.execute(Request::readHoldingRegisters(1, 0, 1));
  EXPECT_EQ(r.error, ErrorKind::kMalformed);
  EXPECT_NE(r.message.find("protocol id 1"), std::string::npos) << r.message;
  EXPECT_FALSE(link.connected());
  ASSERT_TRUE(link.connect(nullptr));
  EXPECT_TRUE(link.execute(Request::readHoldingRegisters(1, 0, 1)).ok());
}

TEST(ModbusTcpLink, DroppedConnectionMidRequestIsAnIoErrorThenReconnects) {
  // The gateway goes away with the request; later connections answer.
  TestTcpServer srv(TcpFraming::kMbap, droppingTheFirstConnection(answeringSeven()));
  ModbusTcpLink link(server(srv.port()));
  ASSERT_TRUE(link.connect(nullptr));
  Request write = Request::writeSingleRegister(1, 3, 5);
  const Result r = link.execute(write);
  EXPECT_EQ(r.error, ErrorKind::kIo) << r.message;
  EXPECT_TRUE(noProperAnswer(r.error));
  EXPECT_FALSE(answerLost(r.error));  // not retried: it may have been carried out
  EXPECT_FALSE(link.connected());
  EXPECT_EQ(srv.received().size(), 1u);  // not resent
  std::string error;
  ASSERT_TRUE(link.connect(&error)) << error;
  EXPECT_TRUE(link.execute(Request::readHoldingRegisters(1, 0, 1)).ok());
  EXPECT_EQ(link.stats().reconnects, 1u);
}

TEST(ModbusTcpLink, AConnectionClosedWhileIdleFailsTheNextRequestAsAnIoError) {
  std::atomic<bool> closed{false};
  TestTcpServer srv(TcpFraming::kMbap, [&](TestTcpServer& s, int fd) {
    const Bytes f = s.readRequest(fd);
    TestTcpServer::write(fd, replyTo(f, {7}));
    shutdown(fd, SHUT_RDWR);  // then the gateway goes away while the bus is idle
    closed = true;
  });
  LinkConfig c = server(srv.port());
  ModbusTcpLink link(c);
  ASSERT_TRUE(link.connect(nullptr));
  ASSERT_TRUE(link.execute(Request::readHoldingRegisters(1, 0, 1)).ok());
  ASSERT_TRUE(waitFor([&] { return closed.load(); }));
  const Result r = link.execute(Request::readHoldingRegisters(1, 0, 1));
  EXPECT_EQ(r.error, ErrorKind::kIo) << r.message;
  EXPECT_FALSE(link.connected());
  EXPECT_EQ(srv.received().size(), 1u);
}

}  // namespace
}  // namespace modbus_rtu_driver
