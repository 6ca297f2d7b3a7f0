#include "modbus_rtu_driver/core/modbus/request_framer.h"

namespace modbus_rtu_driver {

namespace {

// Length of a valid frame starting at `at`, 0 when none starts there. A frame whose function
// code is unknown has no announced length: it is valid when the whole rest has a valid CRC.
size_t validFrameAt(const Bytes& buf, size_t at) {
  const Bytes rest(buf.begin() + static_cast<long>(at), buf.end());
  const int length = requestLengthFromHeader(rest);
  if (length > 0) {
    if (rest.size() < static_cast<size_t>(length)) return 0;
    return hasValidCrc(Bytes(rest.begin(), rest.begin() + length)) ? static_cast<size_t>(length)
                                                                   : 0;
  }
  return length < 0 && rest.size() >= 4 && hasValidCrc(rest) ? rest.size() : 0;
}

}  // namespace

std::vector<Bytes> RequestFramer::take(bool silence) {
  std::vector<Bytes> frames;
  for (;;) {
    // Whole frames as their headers announce them, back to back.
    while (!input_.empty()) {
      const int length = requestLengthFromHeader(input_);
      if (length <= 0 || input_.size() < static_cast<size_t>(length)) break;
      const size_t valid = validFrameAt(input_, 0);
      if (!valid) break;  // noise in front, maybe: wait for the silence
      frames.emplace_back(input_.begin(), input_.begin() + static_cast<long>(valid));
      input_.erase(input_.begin(), input_.begin() + static_cast<long>(valid));
    }
    if (!silence || input_.empty()) return frames;
    size_t skip = 0;
    while (skip < input_.size() && !validFrameAt(input_, skip)) ++skip;
    if (skip > 0) ++dropped_;
    input_.erase(input_.begin(), input_.begin() + static_cast<long>(skip));
    if (input_.empty()) return frames;
    if (requestLengthFromHeader(input_) < 0) {  // unknown function: the rest is one frame
      frames.push_back(input_);
      input_.clear();
      return frames;
    }
  }
}

}  // namespace modbus_rtu_driver
