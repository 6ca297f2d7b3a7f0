// Runs modbus_rtu_commission's device and table commands against a ScriptedTransport, so every
// frame they send is compared byte for byte (with the manuals' frames where the manuals print
// them: golden-frames.tsv).
#pragma once

#include <gtest/gtest.h>

#include <sstream>

#include "golden_frames.h"
#include "modbus_rtu_driver/tools/commission_session.h"
#include "scripted_transport.h"

namespace modbus_rtu_driver {

class CommissionOnScript : public ::testing::Test {
 protected:
  // Runs `args` (after --port) with `input` as what the user types; -1 when they do not parse.
  int run(std::vector<std::string> args, const std::string& input = "") {
    args.insert(args.begin(), {"--port", "/dev/null"});
    cmd_ = CommissionCommand{};
    std::string error;
    if (!parseCommission(args, &cmd_, &error)) {
      ADD_FAILURE() << error;
      return -1;
    }
    out_.str("");
    err_.str("");
    std::istringstream in(input);
    Output output(cmd_.json, out_, err_);
    Session session{cmd_, bus_, output, in, stop_};
    const std::string& c = cmd_.command;
    return c == "read" || c == "write" || c == "watch" ? runTableCommand(session)
                                                       : runDeviceCommand(session);
  }

  // The reply the manual prints to the request it prints; fails when the manual has no such
  // frame.
  static std::string golden(const std::string& request_hex) {
    static const std::vector<GoldenFrame> frames = loadGoldenFrames(GOLDEN_FRAMES_PATH);
    const Bytes request = *fromHex(request_hex);
    for (const auto& g : frames)
      if (g.request == request) return g.response.empty() ? "" : toHex(g.response);
    ADD_FAILURE() << request_hex << " is not a frame of the manuals";
    return "";
  }
  static std::string frame(const Request& r) { return toHex(encodeRequest(r)); }
  static std::string reply(const Request& r, const std::vector<uint16_t>& values = {}) {
    return toHex(encodeReply(r, values));
  }
  static std::string exception(const Request& r, uint8_t code) {
    return toHex(encodeException(r.slave, static_cast<uint8_t>(r.function), code));
  }

  void TearDown() override {
    EXPECT_TRUE(bus_.usedUp()) << "the command sent fewer frames than scripted";
    EXPECT_EQ(bus_.mismatches(), "");
  }

  ScriptedTransport bus_;
  CommissionCommand cmd_;
  std::ostringstream out_, err_;
  std::atomic<bool> stop_{false};
};

}  // namespace modbus_rtu_driver
