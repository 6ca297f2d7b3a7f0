// Byte-exact RTU framing: CRC-16/MODBUS, request encoding and reply decoding. Used by the raw
// path of the link (addresses 0 and 248-255), the scripted transport of the unit tests and the
// simulator, so all three agree with the manuals' frames.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

using Bytes = std::vector<uint8_t>;

uint16_t crc16(const uint8_t* data, size_t length);
inline uint16_t crc16(const Bytes& data) {
  return crc16(data.data(), data.size());
}
// Appends the CRC low byte first, as it travels on the wire.
void appendCrc(Bytes& frame);
// True when the last two bytes are the CRC of the rest.
bool hasValidCrc(const Bytes& frame);

std::string toHex(const Bytes& bytes);             // "01 03 00 FD"
std::optional<Bytes> fromHex(const std::string&);  // accepts spaces, upper or lower case

// The request ADU (slave, PDU, CRC). The request must be valid (Request::validate()).
Bytes encodeRequest(const Request& request);
// The request PDU without slave and CRC (what modbus_send_raw_request takes after the slave).
Bytes encodeRequestPdu(const Request& request);

// The shortest reply ADU there is: an exception (slave, function, code, CRC).
constexpr size_t kShortestReply = 5;
// Length of the normal reply ADU to `request` (exceptions are 5 bytes).
size_t expectedReplyLength(const Request& request);
// How many bytes a reply needs in total, judged from the bytes read so far; 0 = need more to
// tell. Used by the reader so it never waits for a byte timeout after a complete frame.
size_t replyLengthFromHeader(const Request& request, const Bytes& partial);

// Checks a complete reply ADU against its request (CRC, address, function, exception,
// byte count, echo) and extracts the values.
Result decodeReply(const Request& request, const Bytes& reply);

// Server side (simulator, slave role tests): parse a request ADU. Returns nothing when the
// frame is incomplete, has a bad CRC or an unknown layout; `error` says why.
std::optional<Request> decodeRequest(const Bytes& frame, std::string* error = nullptr);
// Length of the request ADU judged from its first bytes; 0 = need more; -1 = cannot tell
// (unknown function code).
int requestLengthFromHeader(const Bytes& partial);
// Replies built by a server.
Bytes encodeReply(const Request& request, const std::vector<uint16_t>& read_values);
Bytes encodeException(uint8_t slave, uint8_t function, uint8_t exception_code);

}  // namespace modbus_rtu_driver
