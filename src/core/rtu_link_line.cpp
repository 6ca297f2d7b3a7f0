// The line discipline of RtuLink: the silence kept between frames, stale input thrown away,
// late replies waited out, and the reply reader for the addresses libmodbus filters out.
#include <modbus/modbus.h>
#include <sys/ioctl.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <thread>

#include "modbus_rtu_driver/core/frame.h"
#include "modbus_rtu_driver/core/rtu_link.h"
#include "modbus_rtu_driver/core/serial_port.h"

namespace modbus_rtu_driver {

namespace {
using Steady = std::chrono::steady_clock;
}  // namespace

void RtuLink::keepGap() {
  const auto ready = last_activity_ + std::chrono::duration_cast<Steady::duration>(
                                          std::chrono::duration<double>(effectiveMinGap(config_)));
  auto now = Steady::now();
  if (now >= ready) return;
  // A few microseconds cost less spun than slept (a sleep is a syscall and a wake-up).
  if (ready - now < std::chrono::microseconds(20)) {
    while (Steady::now() < ready) {
    }
    return;
  }
  // The default timer slack (50 us) would stretch every sub-millisecond gap; this thread owns
  // the line, so it asks for 1 us.
  static thread_local bool slack_set = prctl(PR_SET_TIMERSLACK, 1000UL, 0, 0, 0) == 0;
  (void)slack_set;
  std::this_thread::sleep_until(ready);
}

// Before a request: if a transaction with this slave failed less than late_reply_guard ago,
// its reply may still come, and a different request of the same shape would take it: wait
// until the line has been quiet that long. A retry (the same request) need not wait: a late
// answer to it is the right answer; another slave's request cannot take it (the address
// differs), so a dead device costs the others nothing. Then keep the gap; whatever is still in
// the input (a late reply, noise, a long echo) belongs to nobody. Asking for the byte count
// first is cheaper than a flush on every request.
void RtuLink::prepareLine(const Request& request) {
  const auto now = Steady::now();
  const auto guard = std::chrono::duration_cast<Steady::duration>(
      std::chrono::duration<double>(config_.late_reply_guard));
  for (auto it = unsettled_.begin(); it != unsettled_.end();)
    it = now - it->second.failed_at >= guard ? unsettled_.erase(it) : std::next(it);
  const auto mine = unsettled_.find(request.slave);
  if (mine != unsettled_.end() && mine->second.frame != encodeRequest(request)) {
    awaitQuietLine(mine->second.failed_at + guard);
    unsettled_.clear();  // the line was quiet: nothing late is on its way
  }
  keepGap();
  int pending = 0;
  if (ioctl(modbus_get_socket(ctx_), FIONREAD, &pending) != 0 || pending > 0) {
    modbus_flush(ctx_);
    std::lock_guard<std::mutex> lock(stats_mutex_);
    stats_.stale_bytes += static_cast<uint64_t>(std::max(pending, 0));
  }
}

// Reads and drops bytes until `until`, pushed back by late_reply_guard whenever bytes come
// (1 s at most, so a babbling line cannot stall the bus).
void RtuLink::awaitQuietLine(Steady::time_point until) {
  const int fd = modbus_get_socket(ctx_);
  const auto give_up = Steady::now() + std::chrono::seconds(1);
  uint64_t dropped = 0;
  for (auto now = Steady::now(); now < until && now < give_up; now = Steady::now()) {
    if (waitReadable(fd, std::chrono::duration<double>(until - now).count()) <= 0) break;
    uint8_t junk[256];
    const ssize_t n = read(fd, junk, sizeof junk);
    if (n <= 0) break;
    dropped += static_cast<uint64_t>(n);
    until = Steady::now() + std::chrono::duration_cast<Steady::duration>(
                                std::chrono::duration<double>(config_.late_reply_guard));
  }
  last_activity_ = Steady::now();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.stale_bytes += dropped;
}

// Our own reader for the addresses libmodbus filters out: first byte within the response
// timeout, then byte timeouts, and stop as soon as the header says the frame is complete.
Result RtuLink::readReply(const Request& request) {
  const int fd = modbus_get_socket(ctx_);
  const double first = responseTimeout(request);
  const double between = effectiveByteTimeout(config_);
  Bytes buf;
  size_t need = 0;
  while (need == 0 || buf.size() < need) {
    const int ready = waitReadable(fd, buf.empty() ? first : between);
    if (ready == -1) return fromErrno(request, errno);
    if (ready == 0) {
      if (buf.empty())
        return Result::failure(ErrorKind::kTimeout, request.describe() + ": no reply");
      return Result::failure(ErrorKind::kTimeout,
                             request.describe() + ": truncated reply " + toHex(buf));
    }
    uint8_t chunk[MODBUS_RTU_MAX_ADU_LENGTH];
    const size_t want = need ? need - buf.size() : 1;
    const ssize_t n = read(fd, chunk, std::min(sizeof chunk, std::max<size_t>(want, 1)));
    if (n <= 0) return fromErrno(request, n == 0 ? ECONNRESET : errno);
    buf.insert(buf.end(), chunk, chunk + n);
    need = replyLengthFromHeader(request, buf);
    if (need > MODBUS_RTU_MAX_ADU_LENGTH) need = MODBUS_RTU_MAX_ADU_LENGTH;
  }
  return decodeReply(request, buf);
}

}  // namespace modbus_rtu_driver
