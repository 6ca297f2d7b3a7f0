// The link puts exactly the manuals' bytes on the line and decodes the manuals' replies.
#include <gtest/gtest.h>

#include <ctime>
#include <future>

#include "golden_frames.h"
#include "modbus_rtu_driver/core/link/rtu_link.h"
#include "pty_pair.h"

using namespace modbus_rtu_driver;

namespace {

LinkConfig configFor(const PtyPair& pty) {
  LinkConfig c;
  c.port = pty.path();
  c.response_timeout = 0.5;
  c.retries = 0;
  return c;
}

// The Request the driver means for a golden row.
Request requestFor(const GoldenFrame& g) {
  Request r = *decodeRequest(g.request);
  if (g.slave == 0) {
    r.single_device_at_zero = true;
    r.reply_echoes_request = r.function == FunctionCode::kWriteMultipleRegisters;
  }
  return r;
}

}  // namespace

TEST(RtuLinkGolden, EveryRequestTheDriverSendsIsByteExact) {
  const auto rows = loadGoldenFrames(GOLDEN_FRAMES_PATH);
  int checked = 0;
  for (const auto& g : rows) {
    if (g.device == "dm500_master") continue;  // sent by a master to us, not by the driver
    PtyPair pty;
    RtuLink link(configFor(pty));
    std::string error;
    ASSERT_TRUE(link.connect(&error)) << error;
    const Request request = requestFor(g);
    // Rows without a printed reply are answered as the device would (echo / register values).
    const Bytes reply = !g.response.empty() ? g.response
                        : request.expectsReply()
                            ? encodeReply(request, std::vector<uint16_t>(request.count, 0))
                            : Bytes{};
    auto device = std::async(std::launch::async, [&] {
      Bytes got = pty.read(g.request.size());
      pty.write(reply);
      return got;
    });
    const Result r = link.execute(request);
    const Bytes on_the_line = device.get();
    EXPECT_EQ(toHex(on_the_line), toHex(g.request)) << g.meaning;
    EXPECT_TRUE(r.ok()) << g.meaning << ": " << r.message;
    ++checked;
  }
  EXPECT_GE(checked, 55);
}

TEST(RtuLinkGolden, RepliesDecodeToTheManualsValues) {
  struct Case {
    Request request;
    const char* reply;
    std::vector<uint16_t> values;
  };
  Request at_zero = Request::readHoldingRegisters(0, 0, 1);
  at_zero.single_device_at_zero = true;
  const std::vector<Case> cases = {
      {Request::readCoils(1, 0, 8), "01 01 01 7C 50 69", {0, 0, 1, 1, 1, 1, 1, 0}},
      {Request::readHoldingRegisters(1, 0x80, 1), "01 03 02 00 7C B9 A5", {0x7C}},
      {Request::readHoldingRegisters(0xFF, 0xFD, 1), "FF 03 02 00 01 50 50", {1}},
      {Request::readHoldingRegisters(1, 0xFE, 1), "01 03 02 00 03 F8 45", {3}},
      {at_zero, "00 03 02 00 FF C5 C4", {255}},
      {Request::readDiscreteInputs(255, 0, 8), "FF 02 01 01 51 A0", {1, 0, 0, 0, 0, 0, 0, 0}},
      {Request::readHoldingRegisters(255, 0x3E8, 1), "FF 03 02 00 04 90 53", {4}},
      {Request::readInputRegisters(1, 2, 1), "01 04 02 08 9B FF 5B", {2203}},
      {Request::readInputRegisters(1, 3, 1), "01 04 02 02 DA 39 CB", {730}},
      {Request::readInputRegisters(1, 0, 5),
       "01 04 0A 00 DD 02 71 08 98 02 D5 06 3B 86 51",
       {221, 625, 2200, 725, 1595}},
      {Request::readHoldingRegisters(1, 0, 3),
       "01 03 06 09 C4 07 D0 06 40 D2 E0",
       {2500, 2000, 1600}},
  };
  for (const auto& c : cases) {
    PtyPair pty;
    RtuLink link(configFor(pty));
    ASSERT_TRUE(link.connect(nullptr));
    auto device = std::async(std::launch::async, [&] {
      pty.read(8);
      pty.write(*fromHex(c.reply));
    });
    const Result r = link.execute(c.request);
    device.get();
    ASSERT_TRUE(r.ok()) << c.request.describe() << ": " << r.message;
    EXPECT_EQ(r.values, c.values) << c.request.describe();
  }
}

// The wire observer (wire_log, the benchmark's attribution) sees the bytes that went out and
// came in, in order, with times that follow each other.
TEST(RtuLinkGolden, WireObserverSeesEachFrameWithItsTimes) {
  PtyPair pty;
  RtuLink link(configFor(pty));
  std::vector<WireEvent> events;
  link.setWireObserver([&](const WireEvent& e) { events.push_back(e); });
  std::string error;
  ASSERT_TRUE(link.connect(&error)) << error;
  const Bytes request = *fromHex("01 03 00 80 00 01 85 E2");
  const Bytes reply = *fromHex("01 03 02 00 7C B9 A5");
  auto device = std::async(std::launch::async, [&] {
    Bytes got = pty.read(request.size());
    pty.write(reply);
    return got;
  });
  const Result r = link.execute(Request::readHoldingRegisters(1, 0x80, 1));
  EXPECT_EQ(toHex(device.get()), toHex(request));
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_EQ(events.size(), 2u);
  EXPECT_TRUE(events[0].outgoing);
  EXPECT_EQ(toHex(events[0].frame), toHex(request));
  EXPECT_FALSE(events[1].outgoing);
  EXPECT_EQ(toHex(events[1].frame), toHex(reply));
  EXPECT_LE(events[0].first, events[0].last);
  EXPECT_LE(events[0].last, events[1].first);
  EXPECT_LE(events[1].first, events[1].last);
  // The calling thread's CPU time runs forward, and nothing was spun (not a real-time thread).
  EXPECT_GT(events[0].cpu, 0.0);
  EXPECT_LE(events[0].cpu, events[1].cpu);
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  EXPECT_LE(events[1].cpu, static_cast<double>(now.tv_sec) + now.tv_nsec * 1e-9);
  WireEvent e = events[1];
  e.first = e.last = std::chrono::steady_clock::time_point(std::chrono::microseconds(12500001));
  e.cpu = 0.0042;
  EXPECT_EQ(formatWireEvent(e), "rx 12.500001 12.500001 01 03 02 00 7C B9 A5 cpu=0.004200");
  // A request also says how late the gap's sleep before it woke.
  EXPECT_GE(events[0].gap_late, 0.0);
  e = events[0];
  e.first = e.last = std::chrono::steady_clock::time_point(std::chrono::microseconds(12500001));
  e.cpu = 0.0042;
  e.gap_late = 0.000057;
  e.guard_wait = 0.05;
  EXPECT_EQ(formatWireEvent(e),
            "tx 12.500001 12.500001 01 03 00 80 00 01 85 E2 cpu=0.004200 late=0.000057 "
            "guard=0.050000");
}
