// The line discipline every link keeps on the serial line (its own, or a gateway's far side):
// the silence between frames and the wait for a late reply to die out.
#include <sys/prctl.h>
#include <unistd.h>

#include <thread>

#include "modbus_rtu_driver/core/link.h"

namespace modbus_rtu_driver {

namespace {
using Steady = std::chrono::steady_clock;

Steady::duration seconds(double s) {
  return std::chrono::duration_cast<Steady::duration>(std::chrono::duration<double>(s));
}
}  // namespace

void Link::keepGap() {
  const double gap = minGap();
  if (gap <= 0) return;
  const auto ready = last_activity_ + seconds(gap);
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
// differs), so a dead device costs the others nothing.
void Link::settleLine(int fd, const Request& request) {
  const auto now = Steady::now();
  const auto guard = seconds(config_.late_reply_guard);
  for (auto it = unsettled_.begin(); it != unsettled_.end();)
    it = now - it->second.failed_at >= guard ? unsettled_.erase(it) : std::next(it);
  const auto mine = unsettled_.find(request.slave);
  if (mine != unsettled_.end() && mine->second.frame != encodeRequest(request)) {
    awaitQuietLine(fd, mine->second.failed_at + guard);
    unsettled_.clear();  // the line was quiet: nothing late is on its way
  }
}

// Reads and drops bytes until `until`, pushed back by late_reply_guard whenever bytes come
// (1 s at most, so a babbling line cannot stall the bus).
void Link::awaitQuietLine(int fd, Steady::time_point until) {
  const auto give_up = Steady::now() + std::chrono::seconds(1);
  uint64_t dropped = 0;
  for (auto now = Steady::now(); now < until && now < give_up; now = Steady::now()) {
    if (waitReadable(fd, std::chrono::duration<double>(until - now).count()) <= 0) break;
    uint8_t junk[256];
    const ssize_t n = read(fd, junk, sizeof junk);
    if (n <= 0) break;
    dropped += static_cast<uint64_t>(n);
    until = Steady::now() + seconds(config_.late_reply_guard);
  }
  last_activity_ = Steady::now();
  addStaleBytes(dropped);
}

}  // namespace modbus_rtu_driver
