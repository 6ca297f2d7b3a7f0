// The line discipline every link keeps on the serial line (its own, or a gateway's far side):
// the silence between frames and the wait for a late reply to die out.
#include <sched.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <thread>

#include "modbus_rtu_driver/core/link/link.h"

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
  // Only a real-time bus thread spins the end of a long gap (realtime_priority): it cannot be
  // preempted by the machine's other work while it does, and its user asked for latency.
  static thread_local const bool spin = sched_getscheduler(0) == SCHED_FIFO;
  const auto wake_at = spin ? ready - gapSpinMargin() : ready;
  // What is left of a gap shorter than a sleep's own wake-up cost is spun, at any priority:
  // sleeping it would wake later than spinning ends (a sub-millisecond min_gap, a slow decode).
  const auto now = Steady::now();
  const bool brief = now < ready && ready - now <= kBriefGap;
  if (!brief && now < wake_at) {
    // The default timer slack (50 us) would stretch every sub-millisecond gap; this thread owns
    // the line, so it asks for 1 us.
    static thread_local bool slack_set = prctl(PR_SET_TIMERSLACK, 1000UL, 0, 0, 0) == 0;
    (void)slack_set;
    std::this_thread::sleep_until(wake_at);
    const auto woke = Steady::now();
    const auto late =
        std::clamp<Steady::duration>(woke - wake_at, Steady::duration::zero(), kMaxGapSpin);
    wake_lateness_ += (late - wake_lateness_) / 8;
    gap_late_ = std::max(woke - ready, Steady::duration::zero());
  }
  // The rest is spun: a sleep ends late by the scheduler's wake-up latency, which would add to
  // every back-to-back transaction.
  if (!spin && !brief) return;
  const auto spin_start = Steady::now();
  while (Steady::now() < ready) {
  }
  spun_ += Steady::now() - spin_start;
}

// The margin follows how late wake-ups come, so a quiet machine spins a few microseconds and a
// VM that wakes 100 us late spins about that; never more than kMaxGapSpin per gap.
Steady::duration Link::gapSpinMargin() const {
  return std::min<Steady::duration>(wake_lateness_ * 3 / 2 + std::chrono::microseconds(10),
                                    kMaxGapSpin);
}

// Before a request: if a transaction with this slave failed less than late_reply_guard ago,
// its reply may still come, and a different request of the same shape would take it: wait
// until the line has been quiet that long. A retry (the same request) need not wait: a late
// answer to it is the right answer; another slave's request cannot take it (the address
// differs), so a dead device costs the others nothing.
void Link::settleLine(int fd, const EncodedRequest& request) {
  const auto now = Steady::now();
  const auto guard = seconds(config_.late_reply_guard);
  for (auto it = unsettled_.begin(); it != unsettled_.end();)
    it = now - it->second.failed_at >= guard ? unsettled_.erase(it) : std::next(it);
  const auto mine = unsettled_.find(request.request().slave);
  if (mine != unsettled_.end() && mine->second.frame != request.adu()) {
    awaitQuietLine(fd, mine->second.failed_at + guard);
    unsettled_.clear();  // the line was quiet: nothing late is on its way
  }
}

// Reads and drops bytes until `until`, pushed back by late_reply_guard whenever bytes come
// (1 s at most, so a babbling line cannot stall the bus).
void Link::awaitQuietLine(int fd, Steady::time_point until) {
  const auto began = Steady::now();
  const auto give_up = began + std::chrono::seconds(1);
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
  guard_wait_ = last_activity_ - began;
  addStaleBytes(dropped);
}

}  // namespace modbus_rtu_driver
