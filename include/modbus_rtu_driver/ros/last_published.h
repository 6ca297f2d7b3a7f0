// The last message an adapter published on a latched topic that carries settings read back from
// the device (an LD58A08's PWM, a PDU's limits): every poll reads them again, and a subscriber
// wants a message when they change, not one per poll. Bus thread only, like the publishing.
#pragma once

#include <optional>

namespace modbus_rtu_driver {

template <class Message>
class LastPublished {
 public:
  // Whether `message` differs from the last one (or is the first): then it becomes the last one
  // and the caller publishes it. Compare before stamping: a header's stamp differs every time.
  bool changed(const Message& message) {
    if (last_ && *last_ == message) return false;
    last_ = message;
    return true;
  }

 private:
  std::optional<Message> last_;
};

}  // namespace modbus_rtu_driver
