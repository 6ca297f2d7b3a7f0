#include "modbus_rtu_driver/core/config/link_config.h"

#include <algorithm>

#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

const char* parityName(Parity p) {
  return nameIn(kParityNames, p).data();  // the names are literals: terminated
}

std::optional<Parity> parseParity(std::string_view text, std::string* error) {
  if (auto parity = valueIn(kParityNames, text)) return parity;
  if (error) {
    *error = "'" + std::string(text) + "' is not one of " + namesIn(kParityNames);
    if (auto parity = valueIn(kParityLetters, text))
      *error += std::string(" (write '") + parityName(*parity) + "')";
  }
  return std::nullopt;
}

bool isStandardBaud(int b) {
  return std::find(std::begin(kStandardBauds), std::end(kStandardBauds), b) !=
         std::end(kStandardBauds);
}

std::string standardBaudList() {
  return join(kStandardBauds);
}

char parityLetter(Parity parity) {
  return nameIn(kParityLetters, parity)[0];
}

std::string lineName(int baud, Parity parity) {
  return std::to_string(baud) + " 8" + parityLetter(parity) + "1";
}

std::string validateLinkConfig(const LinkConfig& c) {
  if (!(c.network_allowance >= 0.0 && c.network_allowance <= 10.0))
    return "network_allowance: " + std::to_string(c.network_allowance) + " s is outside 0-10 s";
  if (!isStandardBaud(c.baud))
    return "baud: " + std::to_string(c.baud) + " is not one of " + standardBaudList();
  if (c.data_bits != 7 && c.data_bits != 8)
    return "data_bits: " + std::to_string(c.data_bits) + " is not 7 or 8";
  if (c.stop_bits != 1 && c.stop_bits != 2)
    return "stop_bits: " + std::to_string(c.stop_bits) + " is not 1 or 2";
  if (!(c.response_timeout == 0.0 || (c.response_timeout >= 0.001 && c.response_timeout <= 10.0)))
    return "response_timeout: " + std::to_string(c.response_timeout) +
           " s is outside 0.001-10 s (0 = sized from the baud)";
  if (!(c.late_reply_guard >= 0.0 && c.late_reply_guard <= 1.0))
    return "late_reply_guard: " + std::to_string(c.late_reply_guard) + " s is outside 0-1 s";
  if (!(c.byte_timeout >= 0.0 && c.byte_timeout <= 1.0))
    return "byte_timeout: " + std::to_string(c.byte_timeout) + " s is outside 0-1 s (0 = auto)";
  if (c.retries < 0 || c.retries > 10)
    return "retries: " + std::to_string(c.retries) + " is outside 0-10";
  if (!(c.min_gap >= 0.0 && c.min_gap <= 1.0))
    return "min_gap: " + std::to_string(c.min_gap) + " s is outside 0-1 s (0 = t3.5)";
  return {};
}

int bitsPerCharacter(const LinkConfig& c) {
  return 1 + c.data_bits + (c.parity == Parity::kNone ? 0 : 1) + c.stop_bits;
}

double characterTime(int baud, int bits_per_character) {
  return static_cast<double>(bits_per_character) / (baud > 0 ? baud : 9600);
}

double frameGap(int baud, int bits_per_character) {
  return baud > 19200 ? 0.00175 : 3.5 * characterTime(baud, bits_per_character);
}

double characterTime(const LinkConfig& c) {
  return characterTime(c.baud, bitsPerCharacter(c));
}

double frameGap(const LinkConfig& c) {
  return frameGap(c.baud, bitsPerCharacter(c));
}

double effectiveByteTimeout(const LinkConfig& c) {
  if (c.byte_timeout > 0) return c.byte_timeout;
  // 1.5 characters is the spec's limit, but USB adapters deliver in chunks; 5 ms of slack.
  return 1.5 * characterTime(c) + 0.005;
}

double effectiveMinGap(const LinkConfig& c) {
  return c.min_gap > 0 ? c.min_gap : frameGap(c);
}

double effectiveResponseTimeout(const LinkConfig& c, size_t request_bytes) {
  if (c.response_timeout > 0) return c.response_timeout;
  // The write returns before the request is on the wire: its own time counts.
  return static_cast<double>(request_bytes) * characterTime(c) + frameGap(c) + kTurnaroundAllowance;
}

double gatewayResponseTimeout(const LinkConfig& c, size_t request_bytes, size_t reply_bytes) {
  return effectiveResponseTimeout(c, request_bytes) +
         static_cast<double>(reply_bytes) * characterTime(c) + c.network_allowance;
}

double gatewayByteTimeout(const LinkConfig& c) {
  return effectiveByteTimeout(c) + c.network_allowance;
}

}  // namespace modbus_rtu_driver
