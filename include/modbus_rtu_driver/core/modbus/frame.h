// Byte-exact RTU framing: CRC-16/MODBUS, request encoding and reply decoding. Used by the raw
// path of the link (addresses 0 and 248-255), the scripted transport of the unit tests and the
// simulator, so all three agree with the manuals' frames.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
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

// The request ADU (slave, PDU, CRC). The request must be valid (Request::validate()). For
// servers, tests and tools; a link sends an EncodedRequest's frame instead.
Bytes encodeRequest(const Request& request);

// The shortest reply ADU there is: an exception (slave, function, code, CRC).
constexpr size_t kShortestReply = 5;

// A request as a link runs it: checked and encoded once, where the link takes it, and then only
// read. Every attempt (retries included) sends this frame, the timeouts are sized from it, and
// a write's reply is compared with it; nothing after encode() checks or encodes the request
// again. Only encode() makes one, so holding one means the request was valid.
class EncodedRequest {
 public:
  // The request's frame, or nothing when Request::validate() refuses it: then `refused` (if
  // given) is the kInvalidArgument failure naming the request and its bad field.
  static std::optional<EncodedRequest> encode(const Request& request, Result* refused = nullptr);

  const Request& request() const { return request_; }
  const Bytes& adu() const { return adu_; }             // slave, PDU, CRC: the wire bytes
  size_t replyLength() const { return reply_length_; }  // the normal reply ADU (not 5)

 private:
  EncodedRequest(const Request& request, Bytes adu, size_t reply_length)
      : request_(request), adu_(std::move(adu)), reply_length_(reply_length) {}

  Request request_;
  Bytes adu_;
  size_t reply_length_;
};

// How many bytes a reply needs in total, judged from the bytes read so far; 0 = need more to
// tell. Used by the reader so it never waits for a byte timeout after a complete frame.
size_t replyLengthFromHeader(const Request& request, const Bytes& partial);

// Checks a complete reply ADU against the request sent (CRC, address, function, exception,
// byte count, echo against the sent frame) and extracts the values.
Result decodeReply(const EncodedRequest& sent, const Bytes& reply);

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
