#include "modbus_rtu_driver/core/modbus/mbap.h"

#include <algorithm>

namespace modbus_rtu_driver {

Bytes rtuToMbap(uint16_t transaction, const Bytes& rtu) {
  // unit + PDU: the RTU ADU without its 2 CRC bytes
  const size_t carried = rtu.size() >= 2 ? rtu.size() - 2 : 0;
  Bytes out(6 + carried);
  out[0] = static_cast<uint8_t>(transaction >> 8);
  out[1] = static_cast<uint8_t>(transaction & 0xFF);
  out[4] = static_cast<uint8_t>(carried >> 8);
  out[5] = static_cast<uint8_t>(carried & 0xFF);
  std::copy(rtu.begin(), rtu.begin() + static_cast<std::ptrdiff_t>(carried), out.begin() + 6);
  return out;
}

Bytes mbapToRtu(const Bytes& mbap) {
  if (mbap.size() < kMbapHeaderLength) return {};
  Bytes rtu(mbap.begin() + 6, mbap.end());  // unit id, then the PDU
  appendCrc(rtu);
  return rtu;
}

uint16_t mbapTransaction(const Bytes& mbap) {
  return mbap.size() < 2 ? 0 : static_cast<uint16_t>(mbap[0] << 8 | mbap[1]);
}

int mbapLengthFromHeader(const Bytes& partial, std::string* error) {
  if (partial.size() < 6) return 0;
  const unsigned protocol = static_cast<unsigned>(partial[2] << 8 | partial[3]);
  const unsigned length = static_cast<unsigned>(partial[4] << 8 | partial[5]);
  if (protocol != 0) {
    if (error) *error = "MBAP protocol id " + std::to_string(protocol) + " is not 0 (Modbus)";
    return -1;
  }
  // unit id + function code at least; a PDU is at most 253 bytes
  if (length < 2 || length > 254) {
    if (error) *error = "MBAP length " + std::to_string(length) + " is outside 2-254";
    return -1;
  }
  return static_cast<int>(6 + length);
}

}  // namespace modbus_rtu_driver
