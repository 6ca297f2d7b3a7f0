// A Transport that plays a script of (expected request bytes, reply bytes): the real device
// code runs against it, every frame it sends is compared byte for byte, and a test ends by
// asserting that the script was used up.
#pragma once

#include <deque>
#include <optional>
#include <string>

#include "modbus_rtu_driver/core/link/transport.h"
#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

class ScriptedTransport : public Transport {
 public:
  // `reply_hex` empty = the device stays silent (timeout).
  ScriptedTransport& expect(const std::string& request_hex, const std::string& reply_hex = "") {
    steps_.push_back({*fromHex(request_hex), reply_hex.empty() ? Bytes{} : *fromHex(reply_hex)});
    return *this;
  }
  // Expects `request` and answers what a device would (encodeReply with `values` for reads).
  ScriptedTransport& expectEcho(const std::string& request_hex) {
    const Bytes req = *fromHex(request_hex);
    auto decoded = decodeRequest(req);
    steps_.push_back({req, decoded ? encodeReply(*decoded, {}) : Bytes{}});
    return *this;
  }

  // Checked and encoded once, as a link does (the same refusal of an invalid request).
  Result execute(const Request& request) override {
    Result refused;
    const std::optional<EncodedRequest> encoded = EncodedRequest::encode(request, &refused);
    if (!encoded) return refused;
    const Bytes& sent = encoded->adu();
    ++executed_;
    if (steps_.empty()) {
      mismatches_ += "unexpected request " + toHex(sent) + "\n";
      return Result::failure(ErrorKind::kMalformed, "script exhausted");
    }
    const Step step = steps_.front();
    steps_.pop_front();
    if (sent != step.request) {
      mismatches_ += "expected " + toHex(step.request) + " got " + toHex(sent) + "\n";
      return Result::failure(ErrorKind::kMalformed, "unexpected request");
    }
    if (!request.expectsReply()) return Result::success(request.values);
    if (step.reply.empty())
      return Result::failure(ErrorKind::kTimeout, request.describe() + ": no reply");
    return decodeReply(*encoded, step.reply);
  }

  bool usedUp() const { return steps_.empty(); }
  const std::string& mismatches() const { return mismatches_; }
  int executed() const { return executed_; }

 private:
  struct Step {
    Bytes request, reply;
  };
  std::deque<Step> steps_;
  std::string mismatches_;
  int executed_ = 0;
};

}  // namespace modbus_rtu_driver
