// The share server's connections and answers (issue 24, share bullets), on real sockets with
// ephemeral ports: idle and half-sent clients are closed after idle_timeout and free their slot,
// accepted sockets have TCP keep-alive, a start + quantity past 65535 is exception 02, a client
// that half-closes after its request still gets the answer, and a broadcast is followed by the
// turnaround delay before the next request reaches the bus.
#include <gtest/gtest.h>
#include <netinet/tcp.h>

#include <chrono>

#include "bus_config_fixtures.h"
#include "modbus_rtu_driver/node_config/bus_config.h"
#include "share_test_bus.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

namespace {

ShareConfig withIdle(double idle_timeout, int max_clients = 4) {
  ShareConfig c;
  c.server.idle_timeout = idle_timeout;
  c.server.max_clients = max_clients;
  return c;
}

// The server's end of `client`'s connection, found among this process's descriptors.
int serverSideOf(const TcpClient& client, uint16_t server_port) {
  sockaddr_in mine{};
  socklen_t len = sizeof mine;
  getsockname(client.fd(), reinterpret_cast<sockaddr*>(&mine), &len);
  for (int fd = 0; fd < 4096; ++fd) {
    sockaddr_in local{}, peer{};
    socklen_t a = sizeof local, b = sizeof peer;
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&local), &a) != 0) continue;
    if (getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &b) != 0) continue;
    if (local.sin_family == AF_INET && ntohs(local.sin_port) == server_port &&
        peer.sin_port == mine.sin_port)
      return fd;
  }
  return -1;
}

// A bus that notes when each transaction starts and ends (steady clock).
class TimedBus : public Transport {
 public:
  struct Span {
    uint8_t slave;
    std::chrono::steady_clock::time_point start, end;
  };
  Result execute(const Request& r) override {
    Span s{r.slave, std::chrono::steady_clock::now(), {}};
    Result result = r.slave == kBroadcastAddress ? Result::success(r.values)
                                                 : Result::success(std::vector<uint16_t>(r.count));
    s.end = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(m_);
    spans_.push_back(s);
    return result;
  }
  bool connect(std::string*) override { return true; }
  bool connected() const override { return true; }
  std::vector<Span> spans() {
    std::lock_guard<std::mutex> lock(m_);
    return spans_;
  }

 private:
  std::mutex m_;
  std::vector<Span> spans_;
};

}  // namespace

TEST(ShareIdleTimeout, ASilentClientIsClosedAndFreesItsSlot) {
  ShareFixture f(withIdle(0.3, 1));
  ASSERT_TRUE(f.start());
  TcpClient silent(f.port());
  ASSERT_TRUE(silent.connected());
  ASSERT_TRUE(waitFor([&] { return f.gateway->server().stats().connected == 1; }));
  EXPECT_TRUE(silent.closedByServer()) << "an idle client keeps its slot for ever";
  // Its slot is free again: the next client is served.
  TcpClient next(f.port());
  ASSERT_TRUE(next.send(1, Request::readHoldingRegisters(1, 0, 1)));
  EXPECT_EQ(TcpClient::asRtu(next.receive()),
            encodeReply(Request::readHoldingRegisters(1, 0, 1), {0}));
}

TEST(ShareIdleTimeout, AHalfSentFrameIsClosedToo) {
  ShareFixture f(withIdle(0.3));
  ASSERT_TRUE(f.start());
  TcpClient client(f.port());
  const Bytes frame = rtuToMbap(1, encodeRequest(Request::readHoldingRegisters(1, 0, 1)));
  ASSERT_TRUE(client.sendBytes(Bytes(frame.begin(), frame.begin() + 5)));
  EXPECT_TRUE(client.closedByServer());
  EXPECT_TRUE(waitFor([&] { return f.gateway->server().stats().connected == 0; }));
}

TEST(ShareIdleTimeout, AClientWaitingForTheBusIsNotIdle) {
  ShareFixture f(withIdle(0.2));
  ASSERT_TRUE(f.start());
  TcpClient client(f.port());
  f.bus.hold();
  const Request read = Request::readHoldingRegisters(1, 0, 1);
  ASSERT_TRUE(client.send(7, read));
  ASSERT_TRUE(f.bus.awaitExecuted(1));
  // Several idle timeouts pass while its request is on the bus: the connection stays.
  EXPECT_FALSE(client.closedByServer(1.0));
  f.bus.release();
  EXPECT_EQ(TcpClient::asRtu(client.receive()), encodeReply(read, {0}));
}

TEST(ShareKeepAlive, AcceptedSocketsProbeTheirPeer) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  TcpClient client(f.port());
  ASSERT_TRUE(waitFor([&] { return f.gateway->server().stats().connected == 1; }));
  const int fd = serverSideOf(client, f.port());
  ASSERT_GE(fd, 0);
  int on = 0, idle = 0;
  socklen_t len = sizeof on;
  ASSERT_EQ(getsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &on, &len), 0);
  EXPECT_EQ(on, 1);
  len = sizeof idle;
  ASSERT_EQ(getsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle, &len), 0);
  EXPECT_EQ(idle, kKeepAliveIdle);
}

TEST(ShareAddressRange, StartPlusQuantityPast65535IsException02) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  TcpClient client(f.port());
  const std::vector<Request> past_end = {
      Request::readCoils(1, 0xFFFF, 2),
      Request::readDiscreteInputs(1, 0xFFFF, 2),
      Request::readHoldingRegisters(1, 0xFFFF, 2),
      Request::readInputRegisters(1, 0xFFF0, 17),
      Request::writeMultipleCoils(1, 0xFFFF, {true, true}),
      Request::writeMultipleRegisters(1, 0xFFFE, {1, 2, 3}),
  };
  uint16_t t = 1;
  for (const Request& r : past_end) {
    ASSERT_TRUE(client.send(t, r));
    EXPECT_EQ(TcpClient::asRtu(client.receive()),
              encodeException(1, static_cast<uint8_t>(r.function), kIllegalDataAddress))
        << r.describe();
    ++t;
  }
  // The quantity is checked first: too many from 0xFFFF is 03; the last address alone is fine.
  ASSERT_TRUE(client.send(t++, Request::readHoldingRegisters(1, 0xFFFF, 126)));
  EXPECT_EQ(TcpClient::asRtu(client.receive()), encodeException(1, 0x03, kIllegalDataValue));
  ASSERT_TRUE(client.send(t++, Request::readHoldingRegisters(1, 0xFFFF, 1)));
  EXPECT_EQ(TcpClient::asRtu(client.receive()),
            encodeReply(Request::readHoldingRegisters(1, 0xFFFF, 1), {0}));
  ASSERT_TRUE(client.send(t++, Request::writeSingleRegister(1, 0xFFFF, 9)));
  EXPECT_EQ(TcpClient::asRtu(client.receive()),
            encodeReply(Request::writeSingleRegister(1, 0xFFFF, 9), {9}));
  EXPECT_EQ(f.bus.awaitExecuted(2), true);  // only the last two reached the bus
}

TEST(ShareHalfClose, AClientThatHalfClosesAfterItsRequestGetsTheAnswer) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  TcpClient client(f.port());
  f.bus.hold();
  const Request write = Request::writeSingleRegister(1, 3, 42);
  ASSERT_TRUE(client.send(9, write));
  ASSERT_TRUE(f.bus.awaitExecuted(1));
  ASSERT_EQ(shutdown(client.fd(), SHUT_WR), 0);  // "no more requests", as `nc -N` does
  ASSERT_TRUE(waitFor([&] { return f.gateway->server().stats().half_closed == 1; }));
  f.bus.release();
  const Bytes reply = client.receive();
  EXPECT_EQ(TcpClient::asRtu(reply), encodeReply(write, {42}));
  EXPECT_EQ(mbapTransaction(reply), 9);
  EXPECT_TRUE(client.closedByServer()) << "closed once the answer is sent";
  EXPECT_TRUE(waitFor([&] { return f.gateway->server().stats().connected == 0; }));
}

TEST(ShareBroadcast, TheNextRequestWaitsTheTurnaroundDelay) {
  TimedBus bus;
  BusScheduler scheduler(bus);
  ShareConfig config;
  config.server.port = 0;
  config.broadcast_turnaround = 0.15;
  ShareGateway gateway(scheduler, config);
  scheduler.start();
  std::string error;
  ASSERT_TRUE(gateway.start(&error)) << error;
  TcpClient client(gateway.server().port());
  const Request broadcast = Request::writeSingleRegister(0, 0, 3);
  const Request read = Request::readHoldingRegisters(1, 0, 1);
  // Both sent at once: the read waits in the queue while the broadcast is on the bus.
  Bytes both = rtuToMbap(1, encodeRequest(broadcast));
  const Bytes second = rtuToMbap(2, encodeRequest(read));
  both.insert(both.end(), second.begin(), second.end());
  ASSERT_TRUE(client.sendBytes(both));
  EXPECT_EQ(TcpClient::asRtu(client.receive()), encodeReply(broadcast, {3}));
  EXPECT_EQ(TcpClient::asRtu(client.receive()), encodeReply(read, {0}));
  const auto spans = bus.spans();
  ASSERT_EQ(spans.size(), 2u);
  ASSERT_EQ(spans[0].slave, kBroadcastAddress);
  // A lower bound only (a sleep never ends early): the line was quiet for the whole delay.
  EXPECT_GE(std::chrono::duration<double>(spans[1].start - spans[0].end).count(), 0.15);
  scheduler.stop();
}

TEST(ShareConfigKeys, IdleTimeoutAndTurnaroundAreCheckedWithTheirRange) {
  ShareConfig config;
  config.server.port = 0;
  config.broadcast_turnaround = 1.5;
  MemoryBus bus;
  BusScheduler scheduler(bus);
  {
    ShareGateway gateway(scheduler, config);
    std::string error;
    EXPECT_FALSE(gateway.start(&error));
    EXPECT_EQ(error, "broadcast_turnaround: 1.500000 s is outside 0-1 s");
  }
  config.broadcast_turnaround = 0.1;
  config.server.idle_timeout = -1;
  ShareGateway gateway(scheduler, config);
  std::string error;
  EXPECT_FALSE(gateway.start(&error));
  EXPECT_NE(error.find("idle_timeout"), std::string::npos) << error;

  const std::string base = "port: /dev/ttyUSB0\ndevices: {pdu: {type: yespeed_pdu, address: 2}}\n";
  auto shareError = [&](const std::string& share) {
    return configtest::errorOf(base + "share: " + share);
  };
  BusConfig c;
  std::string e;
  ASSERT_TRUE(parseBusConfig(
      YAML::Load(base + "share: {idle_timeout: 0, broadcast_turnaround: 0.2}"), &c, &e))
      << e;
  EXPECT_EQ(c.share.server.idle_timeout, 0.0);
  EXPECT_EQ(c.share.broadcast_turnaround, 0.2);
  ASSERT_TRUE(parseBusConfig(YAML::Load(base + "share: {}"), &c, &e)) << e;
  EXPECT_EQ(c.share.server.idle_timeout, 60.0);
  EXPECT_NE(shareError("{idle_timeout: -1}").find("share/idle_timeout"), std::string::npos)
      << shareError("{idle_timeout: -1}");
  EXPECT_NE(shareError("{idle_timeout: -1}").find("0-86400 s (0 = never)"), std::string::npos);
  EXPECT_NE(shareError("{broadcast_turnaround: 2}").find("share/broadcast_turnaround"),
            std::string::npos);
  EXPECT_NE(shareError("{broadcast_turnaround: 2}").find("0-1 s"), std::string::npos);
  // answer_within: its range here; its lower bound from the link at start
  // (test_share_answer_bound).
  ASSERT_TRUE(parseBusConfig(YAML::Load(base + "share: {answer_within: 0.9}"), &c, &e)) << e;
  EXPECT_EQ(c.share.answer_within, 0.9);
  ASSERT_TRUE(parseBusConfig(YAML::Load(base + "share: {}"), &c, &e)) << e;
  EXPECT_EQ(c.share.answer_within, 0.0);
  for (const char* bad : {"{answer_within: 0}", "{answer_within: 61}", "{answer_within: -1}"}) {
    EXPECT_NE(shareError(bad).find("share/answer_within"), std::string::npos) << shareError(bad);
    EXPECT_NE(shareError(bad).find("outside 0.001-60 s"), std::string::npos) << shareError(bad);
  }
}
