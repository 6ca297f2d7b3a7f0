#include "modbus_rtu_driver/core/rtu_link.h"

#include <linux/serial.h>
#include <modbus/modbus.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "modbus_rtu_driver/core/frame.h"
#include "modbus_rtu_driver/core/serial_port.h"

namespace modbus_rtu_driver {

namespace {

using Steady = std::chrono::steady_clock;

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

RtuLink::RtuLink(LinkConfig config) : config_(std::move(config)) {}

RtuLink::~RtuLink() {
  disconnect();
}

void RtuLink::setReplyDelay(uint8_t slave, double seconds) {
  reply_delay_[slave] = seconds;
}

LinkStats RtuLink::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
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
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    if (ever_connected_) ++stats_.reconnects;
  }
  ever_connected_ = true;
  last_activity_ = Steady::now();
  return true;
}

void RtuLink::disconnect() {
  closeSerialPort(ctx_);
  ctx_ = nullptr;
}

Result RtuLink::execute(const Request& request) {
  const std::string problem = request.validate();
  if (!problem.empty())
    return Result::failure(ErrorKind::kInvalidArgument, request.describe() + ": " + problem);
  if (!ctx_)
    return Result::failure(ErrorKind::kNotConnected, "port " + config_.port + " is not open");
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.requests;
  }
  if (!request.expectsReply()) return sendBroadcast(request);
  const auto start = Steady::now();
  Result r;
  for (int attempt_no = 0;; ++attempt_no) {
    r = attempt(request);
    if (r.ok() || !answerLost(r.error) || !request.repeatable || attempt_no >= config_.retries ||
        !ctx_)
      break;
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.retries;
  }
  account(r, std::chrono::duration<double>(Steady::now() - start).count());
  return r;
}

Result RtuLink::attempt(const Request& request) {
  prepareLine(request);
  uint32_t sec = 0, usec = 0;
  toTimeval(responseTimeout(request), &sec, &usec);
  modbus_set_response_timeout(ctx_, sec, usec);
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.attempts;
  }
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
  last_activity_ = Steady::now();
  countAttempt(r);
  // A failure (not an answer) may be followed by a late reply. A success keeps an earlier
  // entry: after a retry, the first attempt's reply may be the one taken, the second's late.
  if (!r.ok() && r.error != ErrorKind::kException)
    unsettled_[request.slave] = {last_activity_, encodeRequest(request)};
  if (r.error == ErrorKind::kIo) disconnect();
  return r;
}

double RtuLink::responseTimeout(const Request& request) const {
  return effectiveResponseTimeout(config_, 1 + encodeRequestPdu(request).size() + 2) +
         reply_delay_[request.slave];
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
  if (modbus_send_raw_request(ctx_, raw.data(), static_cast<int>(raw.size())) == -1) {
    Result r = fromErrno(request, errno);
    countAttempt(r);
    account(r, 0);
    if (r.error == ErrorKind::kIo) disconnect();
    return r;
  }
  tcdrain(modbus_get_socket(ctx_));
  last_activity_ = Steady::now();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.attempts;
  ++stats_.broadcasts;
  ++stats_.ok;
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

void RtuLink::account(const Result& r, double latency) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  if (r.ok()) {
    ++stats_.ok;
    stats_.last_latency = latency;
    stats_.mean_latency += (latency - stats_.mean_latency) / static_cast<double>(stats_.ok);
    stats_.max_latency = std::max(stats_.max_latency, latency);
  } else {
    ++stats_.failed;
  }
}

// Every failed attempt by kind, also those a retry made good: a flaky line shows in "crc
// errors" before it costs a transaction.
void RtuLink::countAttempt(const Result& r) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  switch (r.error) {
    case ErrorKind::kNone:
      break;
    case ErrorKind::kTimeout:
      ++stats_.timeouts;
      break;
    case ErrorKind::kCrc:
      ++stats_.crc_errors;
      break;
    case ErrorKind::kWrongAddress:
      ++stats_.wrong_address;
      break;
    case ErrorKind::kException:
      ++stats_.exceptions;
      break;
    case ErrorKind::kMalformed:
      ++stats_.malformed;
      break;
    default:
      ++stats_.io_errors;
      break;
  }
}

}  // namespace modbus_rtu_driver
