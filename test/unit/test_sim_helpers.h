// Helpers of the simulator tests: a device asked with hex frames, a client on the pty opened
// with plain termios, a scratch directory, a simulated line in-process.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/modbus/frame.h"
#include "modbus_rtu_driver/sim/sim_lc_relay8.h"
#include "modbus_rtu_driver/sim/simulator.h"
#include "wait_for.h"

namespace modbus_rtu_driver {
namespace simtest {

using namespace std::chrono_literals;

inline Bytes hex(const std::string& text) {
  auto bytes = fromHex(text);
  EXPECT_TRUE(bytes.has_value()) << text;
  return bytes.value_or(Bytes{});
}

// The device's answer to a frame (given in hex) as the line would dispatch it; "" = silence.
inline std::string ask(SimDevice& d, const std::string& frame_hex,
                       SimClock::time_point now = SimClock::now()) {
  const auto request = decodeRequest(hex(frame_hex));
  if (!request) return "undecodable";
  std::optional<Bytes> reply;
  if (request->slave == kBroadcastAddress) {
    reply = d.handleBroadcast(*request, now);
  } else if (d.answersTo(request->slave, &*request)) {
    reply = d.handle(*request, now);
  }
  return reply ? toHex(*reply) : "";
}
inline std::string ask(SimDevice& d, const Request& r, SimClock::time_point now = SimClock::now()) {
  return ask(d, toHex(encodeRequest(r)), now);
}
inline std::string exceptionHex(uint8_t slave, uint8_t function, uint8_t code) {
  return toHex(encodeException(slave, function, code));
}

inline uint16_t get(SimDevice& d, Table t, uint16_t address,
                    SimClock::time_point now = SimClock::now()) {
  uint16_t v = 0xDEAD;
  EXPECT_EQ(d.read(t, address, now, &v), 0) << "read " << address;
  return v;
}

// A fresh directory under /tmp, removed with everything in it.
class ScratchDir {
 public:
  ScratchDir() {
    char tmpl[] = "/tmp/modbus_rtu_simtest_XXXXXX";
    path_ = mkdtemp(tmpl);
  }
  ~ScratchDir() { std::system(("rm -rf '" + path_ + "'").c_str()); }
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// A simulator of `d` started in `dir`, its link and its state file there.
inline std::unique_ptr<Simulator> started(const ScratchDir& dir,
                                          std::vector<SimulatorConfig::Entry> d) {
  SimulatorConfig config;
  config.devices = std::move(d);
  SimulatorOptions options;
  options.link = dir / "tty";
  options.state_file = dir / "state.yaml";
  auto sim = std::make_unique<Simulator>(config, options);
  std::string error;
  EXPECT_TRUE(sim->start(&error)) << error;
  return sim;
}

// A master on the simulator's link, with the settings a driver would set.
class PtyClient {
 public:
  explicit PtyClient(const std::string& path, speed_t speed = B9600, char parity = 'N') {
    fd_ = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
    EXPECT_GE(fd_, 0) << path;
    configure(speed, parity);
  }
  ~PtyClient() {
    if (fd_ >= 0) close(fd_);
  }
  void configure(speed_t speed, char parity = 'N') {
    termios tio{};
    tcgetattr(fd_, &tio);
    cfmakeraw(&tio);
    cfsetispeed(&tio, speed);
    cfsetospeed(&tio, speed);
    // As libmodbus does: INPCK with the parity (a pty clears PARENB, see pty_link.h).
    tio.c_cflag &= ~static_cast<tcflag_t>(PARENB | PARODD);
    tio.c_iflag &= ~static_cast<tcflag_t>(INPCK);
    if (parity != 'N') {
      tio.c_cflag |= PARENB | (parity == 'O' ? PARODD : 0);
      tio.c_iflag |= INPCK;
    }
    tcsetattr(fd_, TCSANOW, &tio);
  }
  void send(const Bytes& out) {
    ASSERT_EQ(write(fd_, out.data(), out.size()), static_cast<ssize_t>(out.size()));
  }
  // Bytes until `expect` came or `quiet` passed without any.
  Bytes receive(size_t expect, std::chrono::milliseconds quiet = 300ms) {
    Bytes in;
    while (in.size() < expect) {
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(quiet.count())) <= 0) break;
      uint8_t buf[256];
      const ssize_t n = read(fd_, buf, sizeof buf);
      if (n <= 0) break;
      in.insert(in.end(), buf, buf + n);
    }
    return in;
  }
  // The reply to `request` in hex ("" = silence). Stale bytes are dropped first.
  std::string exchange(const Bytes& request, size_t expect = 256,
                       std::chrono::milliseconds quiet = 300ms) {
    receive(256, 0ms);
    send(request);
    return toHex(receive(expect, quiet));
  }
  std::string exchange(const std::string& request_hex, size_t expect = 256,
                       std::chrono::milliseconds quiet = 300ms) {
    return exchange(hex(request_hex), expect, quiet);
  }

 private:
  int fd_ = -1;
};

// A simulated line in-process with its control commands: line("silence 2 1") -> "ok".
class Line {
 public:
  explicit Line(std::vector<SimulatorConfig::Entry> devices, bool pace = false, int baud = 9600) {
    SimulatorConfig config;
    config.devices = std::move(devices);
    config.pace = pace;
    config.factory.baud = baud;
    SimulatorOptions options;
    options.link = dir_ / "tty";
    sim_ = std::make_unique<Simulator>(config, options);
    std::string error;
    EXPECT_TRUE(sim_->start(&error)) << error;
  }
  Simulator& sim() { return *sim_; }
  std::string operator()(const std::string& command) { return sim_->command(command); }
  // Frames the simulator has taken off the line so far: valid ones and runs of bytes it dropped
  // (the "frames" command's RECEIVED + DROPPED).
  uint64_t framesTaken() {
    unsigned long long received = 0, answered = 0, dropped = 0;
    const std::string f = sim_->command("frames");
    if (std::sscanf(f.c_str(), "ok %llu %llu %llu", &received, &answered, &dropped) != 3) return 0;
    return received + dropped;
  }
  // True once the simulator has taken `count` frames off the line (bounded wait). A silence heard
  // by the client says nothing about whether the simulator's thread has read the request yet (a
  // loaded machine): a test waits for this before it checks the devices or changes the line.
  ::testing::AssertionResult tookFrames(uint64_t count) {
    if (waitFor([&] { return framesTaken() >= count; })) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure()
           << "the simulator took " << framesTaken() << " of " << count << " frames within 10 s";
  }
  std::string link() const { return dir_ / "tty"; }

 private:
  ScratchDir dir_;
  std::unique_ptr<Simulator> sim_;
};

}  // namespace simtest
}  // namespace modbus_rtu_driver
