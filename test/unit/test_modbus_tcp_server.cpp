// The share's Modbus TCP server on real sockets (127.0.0.1, an ephemeral port) over a real bus
// thread: replies with the client's transaction id, refusals (read-only, allow list, client
// bound, full queue), bus failures as gateway exceptions, malformed frames, dropClients.
#include <gtest/gtest.h>

#include "share_test_bus.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

namespace {

// The MBAP reply a gateway sends for `request` with `transaction`: the reply ADU or exception.
Bytes expected(uint16_t transaction, const Bytes& rtu) {
  return rtuToMbap(transaction, rtu);
}
Bytes exceptionReply(uint16_t transaction, const Request& r, uint8_t code) {
  return expected(transaction, encodeException(r.slave, static_cast<uint8_t>(r.function), code));
}

}  // namespace

TEST(ShareAddresses, ListenAndAllowEntriesAreChecked) {
  // Text only: nothing here binds or connects.
  std::string host, error;
  uint16_t parsed = 0;
  EXPECT_TRUE(parseListenAddress("127.0.0.1:1502", &host, &parsed, &error));
  EXPECT_EQ(host, "127.0.0.1");
  EXPECT_EQ(parsed, 1502u);
  EXPECT_FALSE(parseListenAddress("localhost:1502", &host, &parsed, &error));
  EXPECT_NE(error.find("IPv4"), std::string::npos) << error;
  EXPECT_FALSE(parseListenAddress("127.0.0.1:0", &host, &parsed, &error));
  EXPECT_NE(error.find("1-65535"), std::string::npos) << error;
  EXPECT_FALSE(parseListenAddress("127.0.0.1:70000", &host, &parsed, &error));
  uint32_t net = 0, mask = 0;
  EXPECT_TRUE(parseAllowEntry("10.1.2.3/8", &net, &mask, &error));
  EXPECT_EQ(net, 0x0A000000u);
  EXPECT_EQ(mask, 0xFF000000u);
  EXPECT_TRUE(parseAllowEntry("0.0.0.0/0", &net, &mask, &error));
  EXPECT_EQ(mask, 0u);
  EXPECT_FALSE(parseAllowEntry("10.0.0.0/33", &net, &mask, &error));
  EXPECT_FALSE(parseAllowEntry("example.com", &net, &mask, &error));
}

TEST(ModbusTcpServer, RepliesCarryTheTransactionIdAndUnit) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  TcpClient c(f.port());
  ASSERT_TRUE(c.connected());
  const Request write = Request::writeSingleRegister(1, 7, 0xBEEF);
  ASSERT_TRUE(c.send(0x1234, write));
  // 12 34 | 00 00 | 00 06 | 01 | 06 00 07 BE EF: the echo, with the client's id
  EXPECT_EQ(toHex(c.receive()), "12 34 00 00 00 06 01 06 00 07 BE EF");
  EXPECT_EQ(f.bus.reg(7), 0xBEEF);
  const Request read = Request::readHoldingRegisters(1, 6, 2);
  ASSERT_TRUE(c.send(0xFFFE, read));
  EXPECT_EQ(c.receive(), expected(0xFFFE, encodeReply(read, {0, 0xBEEF})));
  // Pipelined: three requests in one segment, answered in order, each with its id.
  Bytes three;
  for (uint16_t id : {1, 2, 3}) {
    const Bytes one = rtuToMbap(id, encodeRequest(Request::writeSingleRegister(1, id, id * 10)));
    three.insert(three.end(), one.begin(), one.end());
  }
  ASSERT_TRUE(c.sendBytes(three));
  for (uint16_t id : {1, 2, 3}) {
    const Bytes r = c.receive();
    EXPECT_EQ(mbapTransaction(r), id);
    EXPECT_EQ(f.bus.reg(id), id * 10);
  }
  const auto stats = f.gateway->server().stats();
  EXPECT_EQ(stats.peers.at("127.0.0.1").requests, 5u);
  EXPECT_EQ(stats.peers.at("127.0.0.1").exceptions, 0u);
  EXPECT_EQ(f.bus_thread.health("memory").shared_ok, 5u);
}

TEST(ModbusTcpServer, ReadOnlyRefusesWritesWithIllegalFunction) {
  ShareConfig config;
  config.read_only = true;
  ShareFixture f(config);
  ASSERT_TRUE(f.start());
  TcpClient c(f.port());
  for (const Request& w :
       {Request::writeSingleRegister(1, 3, 9), Request::writeSingleCoil(1, 3, true),
        Request::writeMultipleRegisters(1, 3, {1, 2}),
        Request::writeMultipleCoils(1, 3, {true, false})}) {
    ASSERT_TRUE(c.send(77, w));
    EXPECT_EQ(c.receive(), exceptionReply(77, w, kIllegalFunction)) << w.describe();
  }
  EXPECT_EQ(f.bus.reg(3), 0);
  const Request read = Request::readCoils(1, 0, 8);
  ASSERT_TRUE(c.send(78, read));
  EXPECT_EQ(c.receive(), expected(78, encodeReply(read, std::vector<uint16_t>(8, 0))));
  EXPECT_EQ(f.gateway->server().stats().peers.at("127.0.0.1").exceptions, 4u);
}

// docs/share.md: a write while read_only gets 01, malformed or not. The fields of a write are
// not checked first: 02 / 03 would tell the client how to fix a write that cannot pass anyway.
TEST(ModbusTcpServer, ReadOnlyRefusesMalformedWritesWithIllegalFunctionToo) {
  ShareConfig config;
  config.read_only = true;
  ShareFixture f(config);
  ASSERT_TRUE(f.start());
  TcpClient c(f.port());
  ASSERT_TRUE(c.connected());
  // transaction, unit 1, PDU -> the exception reply
  const std::vector<std::pair<const char*, const char*>> cases = {
      // FC05 with a coil value other than FF00 / 0000 (03 when writable)
      {"00 11 00 00 00 06 01 05 00 00 12 34", "00 11 00 00 00 03 01 85 01"},
      // FC15 with count 0 (03 when writable)
      {"00 12 00 00 00 08 01 0F 00 00 00 00 01 00", "00 12 00 00 00 03 01 8F 01"},
      // FC16 at 0xFFFF for 2 registers: past 65535 (02 when writable)
      {"00 13 00 00 00 0B 01 10 FF FF 00 02 04 00 01 00 02", "00 13 00 00 00 03 01 90 01"},
      // FC16 whose byte count does not match its quantity (03 when writable)
      {"00 14 00 00 00 09 01 10 00 00 00 01 04 00 01", "00 14 00 00 00 03 01 90 01"},
      // FC06 with a PDU too short for its function (03 when writable)
      {"00 15 00 00 00 04 01 06 00 00", "00 15 00 00 00 03 01 86 01"},
      // a well-formed FC06
      {"00 16 00 00 00 06 01 06 00 03 00 09", "00 16 00 00 00 03 01 86 01"},
      // FC22 / FC23 (mask write, read/write multiple): not served at all, 01 as before
      {"00 17 00 00 00 08 01 16 00 03 FF FF 00 00", "00 17 00 00 00 03 01 96 01"},
      {"00 18 00 00 00 0D 01 17 00 00 00 01 00 03 00 01 02 00 07", "00 18 00 00 00 03 01 97 01"},
  };
  for (const auto& [request, answer] : cases) {
    ASSERT_TRUE(c.sendBytes(*fromHex(request))) << request;
    EXPECT_EQ(toHex(c.receive()), answer) << request;
  }
  EXPECT_EQ(f.bus.reg(3), 0);
  EXPECT_EQ(f.bus.reg(0), 0);
  // Reads are still checked as before: FC03 at 0xFFFF for 2 registers is 02, not 01.
  ASSERT_TRUE(c.sendBytes(*fromHex("00 19 00 00 00 06 01 03 FF FF 00 02")));
  EXPECT_EQ(toHex(c.receive()), "00 19 00 00 00 03 01 83 02");
}

TEST(ModbusTcpServer, ClientsOutsideTheAllowListAreClosedAtAccept) {
  ShareConfig config;
  config.server.allow = {"10.0.0.0/8", "192.168.1.7"};
  ShareFixture f(config);
  ASSERT_TRUE(f.start());
  TcpClient c(f.port());
  ASSERT_TRUE(c.connected());  // the kernel accepts; the server closes it at once
  c.send(1, Request::readCoils(1, 0, 8));
  EXPECT_TRUE(c.closedByServer());
  EXPECT_EQ(f.gateway->server().stats().refused_not_allowed, 1u);
  EXPECT_EQ(f.gateway->server().stats().accepted, 0u);
}

TEST(ModbusTcpServer, TheNumberOfClientsIsBounded) {
  ShareConfig config;
  config.server.max_clients = 2;
  ShareFixture f(config);
  ASSERT_TRUE(f.start());
  auto a = std::make_unique<TcpClient>(f.port());
  TcpClient b(f.port());
  ASSERT_TRUE(waitFor([&] { return f.gateway->server().stats().connected == 2; }));
  TcpClient third(f.port());
  EXPECT_TRUE(third.closedByServer());
  EXPECT_EQ(f.gateway->server().stats().refused_too_many, 1u);
  a.reset();  // a place becomes free
  ASSERT_TRUE(waitFor([&] { return f.gateway->server().stats().connected == 1; }));
  TcpClient fourth(f.port());
  const Request read = Request::readHoldingRegisters(1, 0, 1);
  ASSERT_TRUE(fourth.send(4, read));
  EXPECT_EQ(fourth.receive(), expected(4, encodeReply(read, {0})));
}

TEST(ModbusTcpServer, AFullQueueAnswersSlaveDeviceBusy) {
  ShareConfig config;
  config.max_queue = 2;
  ShareFixture f(config);
  ASSERT_TRUE(f.start());
  TcpClient c(f.port());
  f.bus.hold();
  ASSERT_TRUE(c.send(1, Request::writeSingleRegister(1, 1, 11)));
  ASSERT_TRUE(f.bus.awaitExecuted(1));                             // on the bus, held
  ASSERT_TRUE(c.send(2, Request::writeSingleRegister(1, 2, 22)));  // waits in the queue
  ASSERT_TRUE(waitFor([&] { return f.gateway->queued() == 2; }));
  const Request third = Request::writeSingleRegister(1, 3, 33);
  ASSERT_TRUE(c.send(3, third));
  EXPECT_EQ(c.receive(), exceptionReply(3, third, kSlaveDeviceBusy));  // before the others
  f.bus.release();
  EXPECT_EQ(mbapTransaction(c.receive()), 1);
  EXPECT_EQ(mbapTransaction(c.receive()), 2);
  EXPECT_EQ(f.bus.reg(1), 11);
  EXPECT_EQ(f.bus.reg(2), 22);
  EXPECT_EQ(f.bus.reg(3), 0) << "a refused request never reaches the bus";
  ASSERT_TRUE(waitFor([&] { return f.gateway->queued() == 0; }));
  ASSERT_TRUE(c.send(4, third));  // room again
  EXPECT_EQ(c.receive(), expected(4, encodeReply(third, {})));
}

TEST(ModbusTcpServer, BusFailuresBecomeGatewayExceptionsAndDeviceExceptionsPassThrough) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  TcpClient c(f.port());
  const Request silent = Request::readHoldingRegisters(9, 0, 1);  // nobody at 9
  ASSERT_TRUE(c.send(10, silent));
  EXPECT_EQ(c.receive(), exceptionReply(10, silent, kGatewayTargetFailed));
  const Request refused = Request::readHoldingRegisters(5, 0, 1);
  ASSERT_TRUE(c.send(11, refused));
  EXPECT_EQ(c.receive(), exceptionReply(11, refused, kIllegalDataAddress));
  // Unit 0: a broadcast write is answered once sent; a broadcast read cannot be answered.
  const Request broadcast = Request::writeSingleRegister(0, 1, 5);
  ASSERT_TRUE(c.send(12, broadcast));
  EXPECT_EQ(c.receive(), expected(12, encodeReply(broadcast, {})));
  const Request broadcast_read = Request::readHoldingRegisters(0, 1, 1);
  ASSERT_TRUE(c.sendBytes(rtuToMbap(13, encodeRequest(broadcast_read))));
  EXPECT_EQ(c.receive(), exceptionReply(13, broadcast_read, kIllegalFunction));
}

TEST(ModbusTcpServer, AClosedPortIsGatewayPathUnavailable) {
  ShareFixture f;
  f.bus.open = false;
  ASSERT_TRUE(f.start());
  TcpClient c(f.port());
  const Request read = Request::readHoldingRegisters(1, 0, 1);
  ASSERT_TRUE(c.send(20, read));
  EXPECT_EQ(c.receive(), exceptionReply(20, read, kGatewayPathUnavailable));
}

TEST(ModbusTcpServer, MalformedFramesCloseTheClientOrGetAnException) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  {  // a function the server does not know: exception 01, the connection stays
    TcpClient c(f.port());
    ASSERT_TRUE(c.sendBytes(*fromHex("00 05 00 00 00 03 01 2B 0E")));
    EXPECT_EQ(toHex(c.receive()), "00 05 00 00 00 03 01 AB 01");
    // a PDU too short for its function, and a count validate() refuses: exception 03
    ASSERT_TRUE(c.sendBytes(*fromHex("00 06 00 00 00 04 01 03 00 00")));
    EXPECT_EQ(toHex(c.receive()), "00 06 00 00 00 03 01 83 03");
    ASSERT_TRUE(c.sendBytes(*fromHex("00 07 00 00 00 06 01 03 00 00 00 00")));
    EXPECT_EQ(toHex(c.receive()), "00 07 00 00 00 03 01 83 03");
    // a byte count that does not match the quantity
    ASSERT_TRUE(c.sendBytes(*fromHex("00 08 00 00 00 09 01 10 00 00 00 01 04 00 01")));
    EXPECT_EQ(toHex(c.receive()), "00 08 00 00 00 03 01 90 03");
    // a coil value other than FF00 / 0000
    ASSERT_TRUE(c.sendBytes(*fromHex("00 09 00 00 00 06 01 05 00 00 12 34")));
    EXPECT_EQ(toHex(c.receive()), "00 09 00 00 00 03 01 85 03");
    EXPECT_EQ(f.bus.reg(0), 0);
  }
  // headers that are not Modbus TCP: the stream cannot be trusted, the client is closed
  for (const char* header : {"00 01 00 01 00 06 01 03 00 00 00 01",  // protocol id 1
                             "00 01 00 00 00 01 01",                 // length 1
                             "00 01 00 00 01 00 01"}) {              // length 256
    TcpClient c(f.port());
    ASSERT_TRUE(c.sendBytes(*fromHex(header)));
    EXPECT_TRUE(c.closedByServer()) << header;
  }
  EXPECT_EQ(f.gateway->server().stats().malformed, 3u);
  TcpClient after(f.port());  // the server goes on
  const Request read = Request::readHoldingRegisters(1, 0, 1);
  ASSERT_TRUE(after.send(1, read));
  EXPECT_EQ(after.receive(), expected(1, encodeReply(read, {0})));
}

TEST(ModbusTcpServer, DropClientsClosesEveryConnectionAndKeepsListening) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  TcpClient a(f.port()), b(f.port());
  ASSERT_TRUE(waitFor([&] { return f.gateway->server().stats().connected == 2; }));
  f.gateway->server().dropClients();
  EXPECT_TRUE(a.closedByServer());
  EXPECT_TRUE(b.closedByServer());
  TcpClient c(f.port());
  const Request read = Request::readCoils(1, 0, 1);
  ASSERT_TRUE(c.send(3, read));
  EXPECT_EQ(c.receive(), expected(3, encodeReply(read, {0})));
}

TEST(ModbusTcpServer, AnswersToAClientThatLeftAreDropped) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  {
    TcpClient c(f.port());
    f.bus.hold();
    ASSERT_TRUE(c.send(1, Request::writeSingleRegister(1, 1, 1)));
    ASSERT_TRUE(f.bus.awaitExecuted(1));
  }  // gone while its request is on the bus
  // Its FIN looks like a half-close (test_share_connections): the server keeps the connection
  // until the answer is due, sends it into the void, then closes.
  f.bus.release();
  ASSERT_TRUE(waitFor([&] { return f.gateway->queued() == 0; }));
  ASSERT_TRUE(waitFor([&] { return f.gateway->server().stats().connected == 0; }));
  EXPECT_EQ(f.bus.reg(1), 1);  // it ran (every queued job runs once)
  TcpClient next(f.port());
  const Request read = Request::readHoldingRegisters(1, 1, 1);
  ASSERT_TRUE(next.send(2, read));
  EXPECT_EQ(next.receive(), expected(2, encodeReply(read, {1})));
}

// Issue 33 item 2: a second share on a taken port (two buses left on 1502) is told apart from
// other start failures, so the node can name share/listen (docs/share.md, "Several buses").
TEST(ModbusTcpServer, ATakenPortIsReportedAsAddressInUse) {
  TcpServerOptions options;
  options.port = 0;
  ModbusTcpServer first(options, [](const ModbusTcpServer::Incoming&) {});
  std::string error;
  ASSERT_TRUE(first.start(&error)) << error;
  EXPECT_FALSE(first.addressInUse());
  options.port = first.port();
  ModbusTcpServer second(options, [](const ModbusTcpServer::Incoming&) {});
  EXPECT_FALSE(second.start(&error));
  EXPECT_TRUE(second.addressInUse());
  EXPECT_EQ(error, "cannot listen on 127.0.0.1:" + std::to_string(options.port) +
                       ": Address already in use");
  options.host = "10.0.0.1.2";  // another failure: not an address in use
  ModbusTcpServer third(options, [](const ModbusTcpServer::Incoming&) {});
  EXPECT_FALSE(third.start(&error));
  EXPECT_FALSE(third.addressInUse());
}
