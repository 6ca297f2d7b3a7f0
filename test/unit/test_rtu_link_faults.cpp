// The link against a scripted device on a pty: every kind of failure is told apart, and
// nothing from one transaction is read as the answer to the next.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>
#include <future>
#include <thread>

#include "modbus_rtu_driver/core/link/rtu_link.h"
#include "pty_pair.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

namespace {

class RtuLinkFaults : public ::testing::Test {
 protected:
  void SetUp() override {
    LinkConfig c;
    c.port = pty_.path();
    c.response_timeout = 0.3;
    c.retries = 0;
    link_ = std::make_unique<RtuLink>(c);
    std::string error;
    ASSERT_TRUE(link_->connect(&error)) << error;
  }
  // Runs `request` while the device side reads it and answers `reply` after `delay_ms`.
  Result exchange(const Request& request, const Bytes& reply, int delay_ms = 0) {
    auto device = std::async(std::launch::async, [&] {
      pty_.read(encodeRequest(request).size());
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
      pty_.write(reply);
    });
    Result r = link_->execute(request);
    device.get();
    return r;
  }
  static Bytes withCrc(Bytes b) {
    appendCrc(b);
    return b;
  }

  PtyPair pty_;
  std::unique_ptr<RtuLink> link_;
};

}  // namespace

TEST_F(RtuLinkFaults, ExceptionsAreNamed) {
  const char* names[] = {"", "illegal function", "illegal data address", "illegal data value",
                         "slave device failure"};
  for (uint8_t code = 1; code <= 4; ++code) {
    for (uint8_t slave : {1, 255}) {  // libmodbus path and raw path
      const Request req = Request::readHoldingRegisters(slave, 0x0100, 2);
      const Result r = exchange(req, encodeException(slave, 0x03, code));
      EXPECT_EQ(r.error, ErrorKind::kException) << r.message;
      EXPECT_EQ(r.exception_code, code);
      EXPECT_NE(r.message.find(names[code]), std::string::npos) << r.message;
      EXPECT_NE(r.message.find("FC03"), std::string::npos) << r.message;
      EXPECT_NE(r.message.find("0x0100"), std::string::npos) << r.message;
    }
  }
  EXPECT_EQ(link_->stats().exceptions, 8u);
}

TEST_F(RtuLinkFaults, TimeoutCrcAndWrongAddressAreToldApart) {
  for (uint8_t slave : {1, 255}) {
    const Request req = Request::readCoils(slave, 0, 8);
    EXPECT_EQ(exchange(req, {}).error, ErrorKind::kTimeout);
    Bytes bad = withCrc({slave, 0x01, 0x01, 0x05});
    bad.back() ^= 0x55;
    EXPECT_EQ(exchange(req, bad).error, ErrorKind::kCrc) << int(slave);
    const uint8_t other = slave == 1 ? 2 : 254;
    EXPECT_EQ(exchange(req, withCrc({other, 0x01, 0x01, 0x05})).error, ErrorKind::kWrongAddress)
        << int(slave);
    // Truncated: half a frame then silence.
    EXPECT_EQ(exchange(req, {slave, 0x01, 0x01}).error, ErrorKind::kTimeout) << int(slave);
  }
  const LinkStats s = link_->stats();
  EXPECT_EQ(s.timeouts, 4u);
  EXPECT_EQ(s.crc_errors, 2u);
  EXPECT_EQ(s.wrong_address, 2u);
}

TEST_F(RtuLinkFaults, AWriteWhoseEchoDiffersIsNotConfirmed) {
  for (uint8_t slave : {1, 255}) {
    const Request req = Request::writeSingleCoil(slave, 3, true);
    const Result r = exchange(req, withCrc({slave, 0x05, 0x00, 0x03, 0x00, 0x00}));
    EXPECT_EQ(r.error, ErrorKind::kMalformed) << r.message;
  }
}

TEST_F(RtuLinkFaults, ALateReplyIsNotTheAnswerToTheNextRequest) {
  const Request first = Request::readHoldingRegisters(1, 0, 1);
  // The reply to the first request arrives after its timeout (0.3 s) ...
  const Bytes late = withCrc({1, 0x03, 0x02, 0x11, 0x11});
  EXPECT_EQ(exchange(first, late, 450).error, ErrorKind::kTimeout);
  // The late reply is on the link's side of the line before the next request goes out.
  ASSERT_TRUE(waitFor([&] { return pty_.pendingAtClient() >= late.size(); }));
  // ... and must not be taken as the answer to the second.
  const Result second = exchange(first, withCrc({1, 0x03, 0x02, 0x22, 0x22}));
  ASSERT_TRUE(second.ok()) << second.message;
  EXPECT_EQ(second.values, std::vector<uint16_t>{0x2222});
}

TEST_F(RtuLinkFaults, AReplyLateEnoughToMeetTheNextRequestIsNotItsAnswer) {
  // The device answers channel 0's registers 350 ms after the request (timeout 0.3 s): without
  // waiting for a quiet line the link would send channel 1's request at 0.3 s and take that late
  // reply, which has the same shape, for channel 1's values.
  const Request ch0 = Request::readHoldingRegisters(1, 0x00, 3);
  const Request ch1 = Request::readHoldingRegisters(1, 0x10, 3);
  LinkConfig c = link_->config();
  c.late_reply_guard = 0.3;  // room for a loaded machine: the reply is due 50 ms after the timeout
  link_->disconnect();
  link_ = std::make_unique<RtuLink>(c);
  ASSERT_TRUE(link_->connect(nullptr));
  auto device = std::async(std::launch::async, [&] {
    pty_.read(encodeRequest(ch0).size());
    std::this_thread::sleep_for(std::chrono::milliseconds(350));
    pty_.write(withCrc({1, 0x03, 0x06, 0, 1, 0, 1, 0, 1}));
    EXPECT_EQ(toHex(pty_.read(8, 2000)), toHex(encodeRequest(ch1)));
    pty_.write(withCrc({1, 0x03, 0x06, 0, 2, 0, 2, 0, 2}));
  });
  EXPECT_EQ(link_->execute(ch0).error, ErrorKind::kTimeout);
  const Result r = link_->execute(ch1);
  device.get();
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, (std::vector<uint16_t>{2, 2, 2}));
  EXPECT_EQ(link_->stats().stale_bytes, 11u);
}

TEST_F(RtuLinkFaults, ARequestThatIsNotRepeatableIsSentOnce) {
  LinkConfig c;
  c.port = pty_.path();
  c.response_timeout = 0.1;
  c.retries = 3;
  link_->disconnect();  // one owner per port
  RtuLink link(c);
  ASSERT_TRUE(link.connect(nullptr));
  Request req = Request::writeMultipleRegisters(1, 0x0000, {10, 5, 3});
  req.repeatable = false;
  EXPECT_EQ(link.execute(req).error, ErrorKind::kTimeout);
  EXPECT_EQ(toHex(pty_.read(64, 300)), toHex(encodeRequest(req)));  // once, not four times
  EXPECT_EQ(link.stats().attempts, 1u);
  req.repeatable = true;
  EXPECT_EQ(link.execute(req).error, ErrorKind::kTimeout);
  EXPECT_EQ(link.stats().attempts, 5u);
}

TEST_F(RtuLinkFaults, StrayBytesBeforeARequestAreFlushed) {
  const Bytes stray{0xFF, 0x10, 0x00, 0x00, 0x00};  // e.g. the tail of a long echo
  pty_.write(stray);
  // On the link's side of the line before the request goes out (a pty passes them on a moment
  // later; arriving mid-exchange they would be another test).
  ASSERT_TRUE(waitFor([&] { return pty_.pendingAtClient() >= stray.size(); }));
  for (uint8_t slave : {1, 255}) {
    const Result r = exchange(Request::readCoils(slave, 0, 8), withCrc({slave, 0x01, 0x01, 0x81}));
    ASSERT_TRUE(r.ok()) << r.message;
    EXPECT_EQ(r.values[0], 1);
    EXPECT_EQ(r.values[7], 1);
  }
}

TEST_F(RtuLinkFaults, RetriesRepeatAfterATimeoutButNotAfterAnException) {
  LinkConfig c;
  c.port = pty_.path();
  c.response_timeout = 0.2;
  c.retries = 2;
  link_->disconnect();  // one owner per port
  RtuLink link(c);
  ASSERT_TRUE(link.connect(nullptr));
  const Request req = Request::readCoils(1, 0, 8);
  const size_t n = encodeRequest(req).size();
  auto device = std::async(std::launch::async, [&] {
    pty_.read(n);  // first attempt: silence
    pty_.read(n);  // second attempt: answered
    pty_.write(withCrc({1, 0x01, 0x01, 0x01}));
  });
  const Result r = link.execute(req);
  device.get();
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(link.stats().retries, 1u);
  EXPECT_EQ(link.stats().attempts, 2u);
  // The timeout a retry made good still shows by its kind (a flaky line is seen early).
  EXPECT_EQ(link.stats().timeouts, 1u);
  EXPECT_EQ(link.stats().ok, 1u);
  EXPECT_EQ(link.stats().failed, 0u);
  auto device2 = std::async(std::launch::async, [&] {
    pty_.read(n);
    pty_.write(encodeException(1, 0x01, 0x02));
  });
  EXPECT_EQ(link.execute(req).error, ErrorKind::kException);
  device2.get();
  EXPECT_EQ(link.stats().attempts, 3u);  // no retry after an exception
  EXPECT_EQ(link.stats().exceptions, 1u);
  EXPECT_EQ(link.stats().failed, 1u);
}

TEST_F(RtuLinkFaults, BroadcastIsSentAndNotWaitedFor) {
  const Request req = Request::writeSingleCoil(0, 2, true);
  auto device = std::async(std::launch::async, [&] { return pty_.read(8); });
  const auto t0 = std::chrono::steady_clock::now();
  const Result r = link_->execute(req);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_LT(took, 0.3) << "a broadcast must not wait for the response timeout";
  EXPECT_EQ(toHex(device.get()), toHex(encodeRequest(req)));
  EXPECT_EQ(link_->stats().broadcasts, 1u);
}

TEST_F(RtuLinkFaults, InvalidRequestsNeverReachTheLine) {
  Request bad = Request::readHoldingRegisters(1, 0, 200);
  const Result r = link_->execute(bad);
  EXPECT_EQ(r.error, ErrorKind::kInvalidArgument);
  EXPECT_NE(r.message.find("count"), std::string::npos);
  EXPECT_TRUE(pty_.read(1, 100).empty());
}

TEST(RtuLink, ConnectNamesTheMissingPort) {
  LinkConfig c;
  c.port = "/nonexistent/ttyUSB9";
  RtuLink link(c);
  std::string error;
  EXPECT_FALSE(link.connect(&error));
  EXPECT_NE(error.find("/nonexistent/ttyUSB9"), std::string::npos) << error;
  EXPECT_EQ(link.execute(Request::readCoils(1, 0, 1)).error, ErrorKind::kNotConnected);
}

TEST_F(RtuLinkFaults, OneOwnerPerPort) {
  LinkConfig c;
  c.port = pty_.path();
  RtuLink second(c);
  std::string error;
  EXPECT_FALSE(second.connect(&error));
  EXPECT_NE(error.find("in use by another process"), std::string::npos) << error;
  // The holder is named: here this very process (its pid and name, /proc/locks).
  std::ifstream comm_file("/proc/self/comm");
  std::string comm;
  std::getline(comm_file, comm);
  EXPECT_NE(
      error.find("(pid " + std::to_string(getpid()) + ", " + comm + ", holds the port's lock)"),
      std::string::npos)
      << error;
  link_->disconnect();
  EXPECT_TRUE(second.connect(&error)) << error;
}

// A program that ignores locks (mbpoll, a terminal) must not get the port while the link has it:
// the kernel refuses its open() with EBUSY (TIOCEXCL). Root is let through by the kernel, so a
// root test tries as "nobody".
TEST_F(RtuLinkFaults, ProgramsThatIgnoreTheLockCannotOpenThePort) {
  const std::string path = pty_.path();
  const bool root = geteuid() == 0;
  if (root) {
    ASSERT_EQ(chmod(path.c_str(), 0666), 0);
  }
  auto tryOpen = [&] {  // 0: refused with EBUSY, 1: opened, 2: other error
    const pid_t pid = fork();
    if (pid == 0) {
      if (root && (setgid(65534) != 0 || setuid(65534) != 0)) _exit(3);
      const int fd = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
      _exit(fd >= 0 ? 1 : errno == EBUSY ? 0 : 2);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  EXPECT_EQ(tryOpen(), 0);
  link_->disconnect();
  EXPECT_EQ(tryOpen(), 1);  // the exclusivity ends with the link's hold on the port
}
