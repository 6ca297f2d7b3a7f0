#include "modbus_rtu_driver/core/modbus/frame.h"

#include <array>
#include <cctype>
#include <cstdio>

namespace modbus_rtu_driver {

namespace {

// The CRC of each byte value, built at compile time from the polynomial (0xA001, reflected): a
// table lookup a byte instead of eight shifts (every frame is checked or made at least once).
constexpr std::array<uint16_t, 256> crcTable() {
  std::array<uint16_t, 256> table{};
  for (unsigned value = 0; value < 256; ++value) {
    uint16_t crc = static_cast<uint16_t>(value);
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 1) ? static_cast<uint16_t>((crc >> 1) ^ 0xA001) : crc >> 1;
    table[value] = crc;
  }
  return table;
}
constexpr std::array<uint16_t, 256> kCrcTable = crcTable();

}  // namespace

uint16_t crc16(const uint8_t* data, size_t length) {
  uint16_t crc = 0xFFFF;
  for (size_t i = 0; i < length; ++i)
    crc = static_cast<uint16_t>((crc >> 8) ^ kCrcTable[(crc ^ data[i]) & 0xFF]);
  return crc;
}

void appendCrc(Bytes& frame) {
  const uint16_t crc = crc16(frame);
  frame.push_back(static_cast<uint8_t>(crc & 0xFF));
  frame.push_back(static_cast<uint8_t>(crc >> 8));
}

bool hasValidCrc(const Bytes& frame) {
  if (frame.size() < 3) return false;
  const uint16_t crc = crc16(frame.data(), frame.size() - 2);
  return frame[frame.size() - 2] == (crc & 0xFF) && frame[frame.size() - 1] == (crc >> 8);
}

std::string toHex(const Bytes& bytes) {
  std::string out;
  char buf[4];
  for (size_t i = 0; i < bytes.size(); ++i) {
    std::snprintf(buf, sizeof buf, i ? " %02X" : "%02X", bytes[i]);
    out += buf;
  }
  return out;
}

std::optional<Bytes> fromHex(const std::string& text) {
  Bytes out;
  int nibbles = 0;
  uint8_t current = 0;
  for (char c : text) {
    if (std::isspace(static_cast<unsigned char>(c))) {
      if (nibbles == 1) return std::nullopt;
      continue;
    }
    if (!std::isxdigit(static_cast<unsigned char>(c))) return std::nullopt;
    const int v =
        std::isdigit(static_cast<unsigned char>(c)) ? c - '0' : std::toupper(c) - 'A' + 10;
    current = static_cast<uint8_t>((current << 4) | v);
    if (++nibbles == 2) {
      out.push_back(current);
      nibbles = 0;
      current = 0;
    }
  }
  if (nibbles) return std::nullopt;
  return out;
}

namespace {

void put16(Bytes& b, uint16_t v) {
  b.push_back(static_cast<uint8_t>(v >> 8));
  b.push_back(static_cast<uint8_t>(v & 0xFF));
}

uint16_t get16(const Bytes& b, size_t at) {
  return static_cast<uint16_t>((b[at] << 8) | b[at + 1]);
}

Bytes packBits(const std::vector<uint16_t>& bits) {
  Bytes out((bits.size() + 7) / 8, 0);
  for (size_t i = 0; i < bits.size(); ++i)
    if (bits[i]) out[i / 8] |= static_cast<uint8_t>(1u << (i % 8));
  return out;
}

std::string where(const Request& r) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "slave %u, FC%02X %s at address 0x%04X",
                static_cast<unsigned>(r.slave), static_cast<unsigned>(r.function),
                functionName(r.function), static_cast<unsigned>(r.address));
  return buf;
}

}  // namespace

Bytes encodeRequest(const Request& r) {
  // One allocation (a request is encoded for every transaction, issue 50): the longest frame is
  // FC16's, 9 bytes and two a value.
  Bytes adu;
  adu.reserve(9 + 2 * r.values.size());
  adu.push_back(r.slave);
  adu.push_back(static_cast<uint8_t>(r.function));
  put16(adu, r.address);
  switch (r.function) {
    case FunctionCode::kWriteSingleCoil:
      put16(adu, r.values.at(0) ? 0xFF00 : 0x0000);
      break;
    case FunctionCode::kWriteSingleRegister:
      put16(adu, r.values.at(0));
      break;
    case FunctionCode::kWriteMultipleCoils: {
      put16(adu, r.count);
      const Bytes packed = packBits(r.values);
      adu.push_back(static_cast<uint8_t>(packed.size()));
      adu.insert(adu.end(), packed.begin(), packed.end());
      break;
    }
    case FunctionCode::kWriteMultipleRegisters:
      put16(adu, r.count);
      adu.push_back(static_cast<uint8_t>(r.values.size() * 2));
      for (uint16_t v : r.values) put16(adu, v);
      break;
    default:  // reads
      put16(adu, r.count);
  }
  appendCrc(adu);
  return adu;
}

namespace {

// Length of the normal reply ADU to `r` sent as `adu` (exceptions are 5 bytes).
size_t normalReplyLength(const Request& r, const Bytes& adu) {
  switch (r.function) {
    case FunctionCode::kReadCoils:
    case FunctionCode::kReadDiscreteInputs:
      return 5 + (r.count + 7u) / 8;
    case FunctionCode::kReadHoldingRegisters:
    case FunctionCode::kReadInputRegisters:
      return 5 + 2u * r.count;
    default:
      return r.reply_echoes_request ? adu.size() : 8;
  }
}

}  // namespace

std::optional<EncodedRequest> EncodedRequest::encode(const Request& request, Result* refused) {
  const std::string problem = request.validate();
  if (!problem.empty()) {
    if (refused)
      *refused = Result::failure(ErrorKind::kInvalidArgument, request.describe() + ": " + problem);
    return std::nullopt;
  }
  Bytes adu = encodeRequest(request);
  const size_t reply_length = normalReplyLength(request, adu);
  return EncodedRequest(request, std::move(adu), reply_length);
}

size_t replyLengthFromHeader(const Request& r, const Bytes& p) {
  if (p.size() < 2) return 0;
  const uint8_t fc = p[1];
  if (fc & 0x80) return 5;
  if (fc >= 0x01 && fc <= 0x04) return p.size() < 3 ? 0 : 5u + p[2];
  if (fc == 0x10 && r.reply_echoes_request) return p.size() < 7 ? 0 : 9u + p[6];
  return 8;
}

Result decodeReply(const EncodedRequest& encoded, const Bytes& reply) {
  const Request& r = encoded.request();
  if (reply.size() < 5)
    return Result::failure(ErrorKind::kMalformed,
                           where(r) + ": reply too short (" + toHex(reply) + ")");
  if (!hasValidCrc(reply))
    return Result::failure(ErrorKind::kCrc, where(r) + ": bad CRC in reply " + toHex(reply));
  if (reply[0] != r.slave)
    return Result::failure(ErrorKind::kWrongAddress,
                           where(r) + ": reply came from slave " + std::to_string(reply[0]));
  const uint8_t fc = static_cast<uint8_t>(r.function);
  if (reply[1] == (fc | 0x80))
    return Result::failure(ErrorKind::kException,
                           where(r) + ": device answered " + exceptionName(reply[2]), reply[2]);
  if (reply[1] != fc)
    return Result::failure(ErrorKind::kMalformed,
                           where(r) + ": reply has function " + std::to_string(reply[1]));
  const size_t expected = encoded.replyLength();
  if (reply.size() != expected)
    return Result::failure(ErrorKind::kMalformed,
                           where(r) + ": reply is " + std::to_string(reply.size()) +
                               " bytes, expected " + std::to_string(expected));
  // A read's values: one allocation, moved into the result (every poll decodes one, issue 50).
  std::vector<uint16_t> values;
  switch (r.function) {
    case FunctionCode::kReadCoils:
    case FunctionCode::kReadDiscreteInputs:
      if (reply[2] != (r.count + 7) / 8)
        return Result::failure(ErrorKind::kMalformed, where(r) + ": wrong byte count");
      values.reserve(r.count);
      for (uint16_t i = 0; i < r.count; ++i) values.push_back((reply[3 + i / 8] >> (i % 8)) & 1);
      return Result::success(std::move(values));
    case FunctionCode::kReadHoldingRegisters:
    case FunctionCode::kReadInputRegisters:
      if (reply[2] != 2 * r.count)
        return Result::failure(ErrorKind::kMalformed, where(r) + ": wrong byte count");
      values.reserve(r.count);
      for (uint16_t i = 0; i < r.count; ++i) values.push_back(get16(reply, 3 + 2 * i));
      return Result::success(std::move(values));
    default:
      break;
  }
  // Writes: the reply must confirm exactly what was asked.
  const Bytes& sent = encoded.adu();
  const size_t compare = r.reply_echoes_request || r.function == FunctionCode::kWriteSingleCoil ||
                                 r.function == FunctionCode::kWriteSingleRegister
                             ? sent.size() - 2
                             : 6;
  for (size_t i = 1; i < compare; ++i)
    if (reply[i] != sent[i])
      return Result::failure(ErrorKind::kMalformed,
                             where(r) + ": reply " + toHex(reply) + " does not confirm the write");
  return Result::success(r.values);
}

int requestLengthFromHeader(const Bytes& p) {
  if (p.size() < 2) return 0;
  if (!isKnownFunction(p[1])) return -1;
  if (p[1] == 0x0F || p[1] == 0x10) return p.size() < 7 ? 0 : 9 + p[6];
  return 8;
}

std::optional<Request> decodeRequest(const Bytes& f, std::string* error) {
  auto fail = [&](const char* why) -> std::optional<Request> {
    if (error) *error = why;
    return std::nullopt;
  };
  const int length = requestLengthFromHeader(f);
  if (length < 0) return fail("unknown function code");
  if (length == 0 || f.size() < static_cast<size_t>(length)) return fail("incomplete frame");
  if (f.size() != static_cast<size_t>(length)) return fail("frame length does not match header");
  if (!hasValidCrc(f)) return fail("bad CRC");
  Request r;
  r.slave = f[0];
  r.function = static_cast<FunctionCode>(f[1]);
  r.address = get16(f, 2);
  switch (r.function) {
    case FunctionCode::kWriteSingleCoil: {
      const uint16_t raw = get16(f, 4);
      r.count = 1;
      // 0xFF00 and 0x0000 are the only legal values; others stay visible (as 2) so a server
      // can answer "illegal data value".
      r.values = {static_cast<uint16_t>(raw == 0xFF00 ? 1 : raw == 0 ? 0 : 2)};
      break;
    }
    case FunctionCode::kWriteSingleRegister:
      r.count = 1;
      r.values = {get16(f, 4)};
      break;
    case FunctionCode::kWriteMultipleCoils:
      r.count = get16(f, 4);
      if (f[6] != (r.count + 7) / 8) return fail("byte count does not match quantity");
      for (uint16_t i = 0; i < r.count; ++i) r.values.push_back((f[7 + i / 8] >> (i % 8)) & 1);
      break;
    case FunctionCode::kWriteMultipleRegisters:
      r.count = get16(f, 4);
      if (f[6] != 2 * r.count) return fail("byte count does not match quantity");
      for (uint16_t i = 0; i < r.count; ++i) r.values.push_back(get16(f, 7 + 2 * i));
      break;
    default:
      r.count = get16(f, 4);
  }
  return r;
}

Bytes encodeReply(const Request& r, const std::vector<uint16_t>& read_values) {
  Bytes out{r.slave, static_cast<uint8_t>(r.function)};
  switch (r.function) {
    case FunctionCode::kReadCoils:
    case FunctionCode::kReadDiscreteInputs: {
      const Bytes packed = packBits(read_values);
      out.push_back(static_cast<uint8_t>(packed.size()));
      out.insert(out.end(), packed.begin(), packed.end());
      break;
    }
    case FunctionCode::kReadHoldingRegisters:
    case FunctionCode::kReadInputRegisters:
      out.push_back(static_cast<uint8_t>(read_values.size() * 2));
      for (uint16_t v : read_values) put16(out, v);
      break;
    default: {
      if (r.reply_echoes_request) return encodeRequest(r);
      const Bytes req = encodeRequest(r);
      out.assign(req.begin(), req.begin() + 6);
    }
  }
  appendCrc(out);
  return out;
}

Bytes encodeException(uint8_t slave, uint8_t function, uint8_t code) {
  Bytes out{slave, static_cast<uint8_t>(function | 0x80), code};
  appendCrc(out);
  return out;
}

}  // namespace modbus_rtu_driver
