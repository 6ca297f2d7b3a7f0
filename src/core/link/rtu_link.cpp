#include "modbus_rtu_driver/core/link/rtu_link.h"

#include <linux/serial.h>
#include <modbus/modbus.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "modbus_rtu_driver/core/link/serial_port.h"
#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

RtuLink::~RtuLink() {
  disconnect();
}

bool RtuLink::connect(std::string* error) {
  disconnect();
  ctx_ = openSerialPort(config_, error);
  if (!ctx_) return false;
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

Result RtuLink::attempt(const EncodedRequest& request) {
  prepareLine(request);
  Result sent = send(request);
  if (!sent.ok()) return sent;
  return readRtuReply(modbus_get_socket(ctx_), request, effectiveByteTimeout(config_),
                      config_.port);
}

Result RtuLink::sendBroadcast(const EncodedRequest& request) {
  prepareLine(request);
  // Sent, not waited for: 3.1.6's write functions would wait for a reply nobody sends.
  Result sent = send(request);
  if (!sent.ok()) return sent;
  tcdrain(modbus_get_socket(ctx_));
  return Result::success(request.request().values);
}

// libmodbus sends the frame without its CRC (it adds the same CRC again, and drives RTS in
// RS485 mode). Sending fails only as the port does (the request was validated): an i/o error,
// which disconnects.
Result RtuLink::send(const EncodedRequest& request) {
  const Bytes& frame = request.adu();
  const auto start = std::chrono::steady_clock::now();
  const double cpu = observingWire() ? wireCpuSeconds() : 0;
  if (modbus_send_raw_request(ctx_, frame.data(), static_cast<int>(frame.size() - 2)) == -1)
    return Result::failure(ErrorKind::kIo, request.request().describe() + ": " + config_.port +
                                               ": " + modbus_strerror(errno));
  noteWire(true, start, std::chrono::steady_clock::now(), frame, cpu);
  return Result::success();
}

// Late replies first (the guard), then the gap; whatever is still in the input (a late reply,
// noise, a long echo) belongs to nobody. Asking for the byte count first is cheaper than a
// flush on every request.
void RtuLink::prepareLine(const EncodedRequest& request) {
  settleLine(modbus_get_socket(ctx_), request);
  keepGap();
  int pending = 0;
  if (ioctl(modbus_get_socket(ctx_), FIONREAD, &pending) != 0 || pending > 0) {
    modbus_flush(ctx_);
    addStaleBytes(static_cast<uint64_t>(std::max(pending, 0)));
  }
}

namespace {

bool parseDevicePath(const std::string& port, const std::string& /*rest*/, LinkTarget* out,
                     std::string* /*error*/) {
  out->path = port;  // whatever opens: the open says what is wrong with it
  return true;
}

std::unique_ptr<Link> make(const LinkConfig& config, const LinkTarget& target) {
  return std::make_unique<RtuLink>(config, target);
}

// A port without a scheme.
const LinkType kSerialLink{"",
                           "serial RTU",
                           "a serial device such as /dev/ttyUSB0",
                           "a device path",
                           "RTU frames on a local serial port (an RS485 adapter)",
                           /*networked=*/false,
                           /*answers_for_silence=*/false,
                           parseDevicePath,
                           make};
const bool kRegistered = linkTypes().add(kSerialLink);

}  // namespace

}  // namespace modbus_rtu_driver
