#include "modbus_rtu_driver/core/rtu_link.h"

#include <linux/serial.h>
#include <modbus/modbus.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "modbus_rtu_driver/core/frame.h"
#include "modbus_rtu_driver/core/serial_port.h"

namespace modbus_rtu_driver {

namespace {

#if LIBMODBUS_VERSION_CHECK(3, 1, 7)
constexpr bool kHasQuirks = true;
#else
constexpr bool kHasQuirks = false;
#endif

void toTimeval(double seconds, uint32_t* sec, uint32_t* usec) {
  *sec = static_cast<uint32_t>(seconds);
  *usec = static_cast<uint32_t>(std::lround((seconds - *sec) * 1e6));
  if (*usec >= 1000000) {
    ++*sec;
    *usec -= 1000000;
  }
}

}  // namespace

RtuLink::~RtuLink() {
  disconnect();
}

bool RtuLink::connect(std::string* error) {
  disconnect();
  ctx_ = openSerialPort(config_, error);
  if (!ctx_) return false;
#if LIBMODBUS_VERSION_CHECK(3, 1, 7)
  // Newer libmodbus can address 248-255 itself.
  modbus_enable_quirks(ctx_, MODBUS_QUIRK_MAX_SLAVE);
#endif
  if (config_.direction != DirectionControl::kAuto) {
    // Kernel RS485 mode where the driver has it; plain RTS toggling otherwise.
    modbus_rtu_set_serial_mode(ctx_, MODBUS_RTU_RS485);
    const int mode =
        config_.direction == DirectionControl::kRtsHigh ? MODBUS_RTU_RTS_UP : MODBUS_RTU_RTS_DOWN;
    if (modbus_rtu_set_rts(ctx_, mode) == -1) {
      if (error) *error = "cannot drive RTS on " + config_.port + ": " + modbus_strerror(errno);
      disconnect();
      return false;
    }
  }
  uint32_t sec = 0, usec = 0;
  toTimeval(effectiveByteTimeout(config_), &sec, &usec);
  modbus_set_byte_timeout(ctx_, sec, usec);
  low_latency_ = false;
  if (config_.low_latency) {
    // USB adapters hold replies up to their latency timer (16 ms on FTDI) without this.
    serial_struct ss{};
    const int fd = modbus_get_socket(ctx_);
    if (ioctl(fd, TIOCGSERIAL, &ss) == 0) {
      ss.flags |= ASYNC_LOW_LATENCY;
      low_latency_ = ioctl(fd, TIOCSSERIAL, &ss) == 0;
    }
  }
  noteConnected();
  return true;
}

void RtuLink::disconnect() {
  closeSerialPort(ctx_);
  ctx_ = nullptr;
}

Result RtuLink::attempt(const Request& request) {
  prepareLine(request);
  uint32_t sec = 0, usec = 0;
  toTimeval(responseTimeout(request), &sec, &usec);
  modbus_set_response_timeout(ctx_, sec, usec);
  const bool libmodbus_can_address =
      request.slave != kBroadcastAddress && (request.slave <= kMaxStandardSlave || kHasQuirks);
  Result r;
  if (!libmodbus_can_address || request.reply_echoes_request) {
    r = exchangeRaw(request, true);
  } else if (isReadFunction(request.function)) {
    r = readViaLibmodbus(request);
  } else {
    // Writes: libmodbus receives, we compare the echo byte for byte (3.1.6 checks only lengths).
    r = exchangeRaw(request, false);
  }
  return r;
}

Result RtuLink::readViaLibmodbus(const Request& request) {
  modbus_set_slave(ctx_, request.slave);
  std::vector<uint16_t> values(request.count);
  int rc = -1;
  if (request.function == FunctionCode::kReadCoils ||
      request.function == FunctionCode::kReadDiscreteInputs) {
    std::vector<uint8_t> bits(request.count);
    rc = request.function == FunctionCode::kReadCoils
             ? modbus_read_bits(ctx_, request.address, request.count, bits.data())
             : modbus_read_input_bits(ctx_, request.address, request.count, bits.data());
    std::copy(bits.begin(), bits.end(), values.begin());
  } else {
    rc = request.function == FunctionCode::kReadHoldingRegisters
             ? modbus_read_registers(ctx_, request.address, request.count, values.data())
             : modbus_read_input_registers(ctx_, request.address, request.count, values.data());
  }
  if (rc == -1) return fromErrno(request, errno);
  if (rc != request.count)
    return Result::failure(ErrorKind::kMalformed,
                           request.describe() + ": " + std::to_string(rc) + " values in the reply");
  return Result::success(values);
}

Result RtuLink::exchangeRaw(const Request& request, bool read_reply_ourselves) {
  Bytes raw{request.slave};
  const Bytes pdu = encodeRequestPdu(request);
  raw.insert(raw.end(), pdu.begin(), pdu.end());
  if (modbus_send_raw_request(ctx_, raw.data(), static_cast<int>(raw.size())) == -1)
    return fromErrno(request, errno);
  if (read_reply_ourselves) return readReply(request);
  modbus_set_slave(ctx_, request.slave);
  uint8_t reply[MODBUS_RTU_MAX_ADU_LENGTH];
  const int rc = modbus_receive_confirmation(ctx_, reply);
  if (rc == -1) return fromErrno(request, errno);
  if (rc == 0)  // 3.1.6 drops a reply from another slave and says so with 0
    return Result::failure(ErrorKind::kWrongAddress,
                           request.describe() + ": reply came from another slave");
  return decodeReply(request, Bytes(reply, reply + rc));
}

Result RtuLink::sendBroadcast(const Request& request) {
  prepareLine(request);
  Bytes raw{request.slave};
  const Bytes pdu = encodeRequestPdu(request);
  raw.insert(raw.end(), pdu.begin(), pdu.end());
  // Sent, not waited for: 3.1.6's write functions would wait for a reply nobody sends.
  if (modbus_send_raw_request(ctx_, raw.data(), static_cast<int>(raw.size())) == -1)
    return fromErrno(request, errno);
  tcdrain(modbus_get_socket(ctx_));
  return Result::success(request.values);
}

Result RtuLink::fromErrno(const Request& request, int error) const {
  const std::string what = request.describe() + ": ";
  if (error > MODBUS_ENOBASE && error <= EMBXGTAR) {
    const auto code = static_cast<uint8_t>(error - MODBUS_ENOBASE);
    return Result::failure(ErrorKind::kException, what + "device answered " + exceptionName(code),
                           code);
  }
  switch (error) {
    case ETIMEDOUT:
      return Result::failure(ErrorKind::kTimeout, what + "no reply");
    case EMBBADCRC:
      return Result::failure(ErrorKind::kCrc, what + "bad CRC in reply");
#ifdef EMBBADSLAVE
    case EMBBADSLAVE:
      return Result::failure(ErrorKind::kWrongAddress, what + "reply came from another slave");
#endif
    case EMBBADDATA:
    case EMBMDATA:
    case EMBBADEXC:
      return Result::failure(ErrorKind::kMalformed, what + modbus_strerror(error));
    default:
      return Result::failure(ErrorKind::kIo, what + config_.port + ": " + modbus_strerror(error));
  }
}

// Late replies first (the guard), then the gap; whatever is still in the input (a late reply,
// noise, a long echo) belongs to nobody. Asking for the byte count first is cheaper than a
// flush on every request.
void RtuLink::prepareLine(const Request& request) {
  settleLine(modbus_get_socket(ctx_), request);
  keepGap();
  int pending = 0;
  if (ioctl(modbus_get_socket(ctx_), FIONREAD, &pending) != 0 || pending > 0) {
    modbus_flush(ctx_);
    addStaleBytes(static_cast<uint64_t>(std::max(pending, 0)));
  }
}

// Our own reader for the addresses libmodbus filters out: first byte within the response
// timeout, then byte timeouts, and stop as soon as the header says the frame is complete.
Result RtuLink::readReply(const Request& request) {
  Bytes reply;
  int error = 0;
  const ReadStatus status = readFrame(
      modbus_get_socket(ctx_), responseTimeout(request), effectiveByteTimeout(config_),
      [&](const Bytes& b) { return static_cast<long>(replyLengthFromHeader(request, b)); },
      kShortestReply, MODBUS_RTU_MAX_ADU_LENGTH, &reply, &error);
  if (status == ReadStatus::kComplete) return decodeReply(request, reply);
  if (status == ReadStatus::kError) return fromErrno(request, error);
  if (status == ReadStatus::kClosed) return fromErrno(request, ECONNRESET);
  return readFailure(request, status, reply, error, config_.port);
}

}  // namespace modbus_rtu_driver
