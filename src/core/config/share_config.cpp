#include "modbus_rtu_driver/core/config/share_config.h"

#include <arpa/inet.h>

namespace modbus_rtu_driver {

namespace {

bool parseIpv4(const std::string& text, uint32_t* host_order) {
  in_addr a{};
  if (inet_pton(AF_INET, text.c_str(), &a) != 1) return false;
  *host_order = ntohl(a.s_addr);
  return true;
}

}  // namespace

bool parseListenAddress(const std::string& text, std::string* host, uint16_t* port,
                        std::string* error) {
  const size_t colon = text.rfind(':');
  uint32_t ip = 0;
  if (colon == std::string::npos || !parseIpv4(text.substr(0, colon), &ip)) {
    if (error) *error = "'" + text + "' is not HOST:PORT with an IPv4 host (127.0.0.1:1502)";
    return false;
  }
  const std::string digits = text.substr(colon + 1);
  const bool numeric = !digits.empty() && digits.size() <= 5 &&
                       digits.find_first_not_of("0123456789") == std::string::npos;
  const long p = numeric ? std::stol(digits) : 0;
  if (p < 1 || p > 65535) {
    if (error) *error = "port '" + digits + "' is outside 1-65535";
    return false;
  }
  *host = text.substr(0, colon);
  *port = static_cast<uint16_t>(p);
  return true;
}

bool parseAllowEntry(const std::string& entry, uint32_t* network, uint32_t* mask,
                     std::string* error) {
  const size_t slash = entry.find('/');
  int bits = 32;
  if (slash != std::string::npos) {
    const std::string digits = entry.substr(slash + 1);
    const bool numeric = !digits.empty() && digits.size() <= 2 &&
                         digits.find_first_not_of("0123456789") == std::string::npos;
    bits = numeric ? std::stoi(digits) : -1;
  }
  uint32_t ip = 0;
  if (!parseIpv4(entry.substr(0, slash), &ip) || bits < 0 || bits > 32) {
    if (error) *error = "'" + entry + "' is not an IPv4 address or block (10.0.0.0/8)";
    return false;
  }
  *mask = bits == 0 ? 0 : ~uint32_t{0} << (32 - bits);
  *network = ip & *mask;
  return true;
}

}  // namespace modbus_rtu_driver
