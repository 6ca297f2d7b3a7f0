// The part of every link that does not depend on the medium: retries, statistics, failures;
// and the line discipline every link keeps on the serial line (its own, or a gateway's far
// side): the silence between frames and the wait for a late reply to die out.
#include "modbus_rtu_driver/core/link/link.h"

#include <sched.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <thread>

namespace modbus_rtu_driver {

namespace {
using Steady = std::chrono::steady_clock;

Steady::duration seconds(double s) {
  return std::chrono::duration_cast<Steady::duration>(std::chrono::duration<double>(s));
}
}  // namespace

std::string formatWireEvent(const WireEvent& e) {
  const auto since_epoch = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(t.time_since_epoch()).count();
  };
  char times[64], cpu[80];
  std::snprintf(times, sizeof times, " %.6f %.6f ", since_epoch(e.first), since_epoch(e.last));
  std::snprintf(cpu, sizeof cpu, e.outgoing ? " cpu=%.6f late=%.6f guard=%.6f" : " cpu=%.6f", e.cpu,
                e.gap_late, e.guard_wait);
  return (e.outgoing ? "tx" : "rx") + std::string(times) + toHex(e.frame) + cpu;
}

void Link::noteWire(bool outgoing, std::chrono::steady_clock::time_point first,
                    std::chrono::steady_clock::time_point last, const Bytes& frame, double cpu) {
  if (!wire_observer_) return;
  WireEvent e{outgoing, first, last, frame, cpu, 0};
  if (outgoing) {
    e.gap_late = std::chrono::duration<double>(gap_late_).count();
    e.guard_wait = std::chrono::duration<double>(guard_wait_).count();
    gap_late_ = guard_wait_ = {};
  }
  wire_observer_(e);
}

double Link::wireCpuSeconds() const {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9 -
         std::chrono::duration<double>(spun_).count();
}

LinkStats Link::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

void Link::noteConnected() {
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    if (ever_connected_) ++stats_.reconnects;
  }
  ever_connected_ = true;
  unsettled_.clear();  // a new connection carries nothing from the old one
  last_activity_ = lineNow();
}

Result Link::execute(const Request& asked) {
  return executeAttempts(asked, 0, -1);
}

Result Link::executeAttempts(const Request& asked, int first, int most) {
  // The one check and the one encoding of this request: every stage after this (each attempt's
  // send, its timeouts, the reply's echo check, the late-reply guard) reads this frame.
  Result refused;
  const std::optional<EncodedRequest> encoded = EncodedRequest::encode(asked, &refused);
  if (!encoded) return refused;
  const EncodedRequest& request = *encoded;
  if (!connected())
    return Result::failure(ErrorKind::kNotConnected, "port " + config_.port + " is not open");
  {
    // A transaction's later attempts (first > 0) are its retries, not a request of their own.
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++(first > 0 ? stats_.retries : stats_.requests);
  }
  if (!asked.expectsReply()) return runBroadcast(request);
  const auto start = Steady::now();
  Result r;
  for (int attempt_no = first;; ++attempt_no) {
    retrying_ = attempt_no > 0;
    r = runAttempt(request);
    // Only a lost answer is retried, and only when doing it twice does no harm; a dropped
    // connection (kIo) is not: the request may have gone out, and the caller reads back.
    if (r.ok() || !answerLost(r.error) || !asked.repeatable || attempt_no >= config_.retries ||
        !connected())
      break;
    if (most >= 0 && attempt_no + 1 - first >= most) {
      // The rest of the transaction comes later: its account then (the retries counted there).
      r.retry_owed = true;
      return r;
    }
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.retries;
  }
  account(r, std::chrono::duration<double>(Steady::now() - start).count());
  return r;
}

Result Link::runAttempt(const EncodedRequest& request) {
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.attempts;
  }
  settled_at_ = lineNow();  // the guard's wait, if any, moves it (guardUntil, lineSettled)
  Result r = attempt(request);
  // The silence after a reply runs from its last byte as read, not from after its decoding.
  last_activity_ = heard_at_.value_or(lineNow());
  heard_at_.reset();
  countAttempt(r);
  // A failure (not an answer) may be followed by a late reply, counted from when that reply
  // would have timed out (the gap, the frame and the silence after it, then the response
  // timeout, from when the request went through the guard): also when the attempt ended early
  // on another frame (noise, a garbled reply, another's reply). A success keeps an earlier
  // entry, moved on: after a retry, the first attempt's reply may be the one taken, and this
  // attempt's own reply is then the late one (the simulation's late replies found each of these
  // guards run out too early, and the next request take the reply: stop 56).
  const double frame = (static_cast<double>(request.adu().size()) + 3.5) * characterTime(config_);
  const auto own_reply_by =
      std::max(last_activity_, settled_at_ + seconds(minGap() + frame + responseTimeout(request)));
  const auto unsettled = unsettled_.find(request.request().slave);
  if (!r.ok() && r.error != ErrorKind::kException)
    unsettled_[request.request().slave] = {own_reply_by, request.adu()};
  else if (r.ok() && unsettled != unsettled_.end())
    unsettled->second.failed_at = std::max(unsettled->second.failed_at, own_reply_by);
  if (r.error == ErrorKind::kIo) disconnect();
  return r;
}

Result Link::runBroadcast(const EncodedRequest& request) {
  Result r = sendBroadcast(request);
  last_activity_ = lineNow();
  if (!r.ok()) {  // not sent: not an attempt
    countAttempt(r);
    account(r, 0);
    if (r.error == ErrorKind::kIo) disconnect();
    return r;
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.attempts;
  ++stats_.broadcasts;
  ++stats_.ok;
  return Result::success(request.request().values);
}

double Link::worstTransactionSeconds(const Request& asked) const {
  const std::optional<EncodedRequest> encoded = EncodedRequest::encode(asked);
  return encoded ? worstSeconds(*encoded) : 0.0;
}

double Link::attemptWorstSeconds(const EncodedRequest& encoded) const {
  const double character = characterTime(config_);
  const double send = minGap() + static_cast<double>(encoded.adu().size()) * character;
  if (!encoded.request().expectsReply()) return send;
  const size_t reply = std::max<size_t>(encoded.replyLength(), kShortestReply);
  return send + responseTimeout(encoded) + static_cast<double>(reply) * character +
         effectiveByteTimeout(config_);
}

double Link::worstSeconds(const EncodedRequest& encoded) const {
  const Request& asked = encoded.request();
  if (!asked.expectsReply()) return attemptWorstSeconds(encoded);
  const int attempts = asked.repeatable ? 1 + std::max(0, config_.retries) : 1;
  return attempts * attemptWorstSeconds(encoded) + config_.late_reply_guard;
}

double Link::lineSeconds(const Request& request) const {
  const std::optional<EncodedRequest> encoded = EncodedRequest::encode(request);
  return encoded ? worstSeconds(*encoded) - config_.late_reply_guard : -1;
}

double Link::attemptSeconds(const Request& request) const {
  const std::optional<EncodedRequest> encoded = EncodedRequest::encode(request);
  return encoded ? attemptWorstSeconds(*encoded) : -1;
}

double Link::guardLeft(const Request& next) const {
  // Most requests find no failed transaction of their slave: no encoding for them.
  if (!guardsLateReplies() || unsettled_.count(next.slave) == 0) return 0;
  const std::optional<EncodedRequest> encoded = EncodedRequest::encode(next);
  // `next` is a new transaction (the scheduler's), whatever the last attempt was.
  const Unsettled* guard = encoded ? holding(*encoded, false) : nullptr;
  if (!guard) return 0;
  const auto left = guard->failed_at + seconds(config_.late_reply_guard) - lineNow();
  return std::max(0.0, std::chrono::duration<double>(left).count());
}

double Link::responseTimeout(const EncodedRequest& request) const {
  return effectiveResponseTimeout(config_, request.adu().size()) +
         reply_delay_[request.request().slave];
}

Result Link::readFailure(const Request& request, ReadStatus status, const Bytes& partial, int error,
                         const std::string& medium) const {
  const std::string what = request.describe() + ": ";
  switch (status) {
    case ReadStatus::kTimeout:
      return Result::failure(ErrorKind::kTimeout, partial.empty()
                                                      ? what + "no reply"
                                                      : what + "truncated reply " + toHex(partial));
    case ReadStatus::kClosed:
      // Sent, so it may have been carried out: a kIo is not retried, and the caller reads back.
      return Result::failure(ErrorKind::kIo, what + medium +
                                                 " closed the connection before the reply (the "
                                                 "request may have been carried out)");
    case ReadStatus::kBadHeader:
      return Result::failure(ErrorKind::kMalformed, what + "not a reply: " + toHex(partial));
    default:
      return Result::failure(ErrorKind::kIo, what + medium + ": " + std::strerror(error));
  }
}

ReadStatus Link::readObserved(int fd, double first, double between,
                              const std::function<long(const Bytes&)>& length_of, size_t shortest,
                              size_t max_length, Bytes* out, int* error) {
  ReadTimes times;
  const ReadStatus status =
      readFrame(fd, first, between, length_of, shortest, max_length, out, error, &times);
  if (status == ReadStatus::kComplete) heard_at_ = times.last;
  if (!out->empty() && observingWire())
    noteWire(false, times.first, times.last, *out, wireCpuSeconds());
  return status;
}

Result Link::readRtuReply(int fd, const EncodedRequest& request, double byte_timeout,
                          const std::string& medium) {
  // The bus thread's one buffer for replies: its capacity stays, so a reply costs no allocation
  // (issue 50).
  Bytes& reply = reply_buffer_;
  reply.reserve(kMaxAduLength);
  int error = 0;
  const ReadStatus status = readObserved(
      fd, responseTimeout(request), byte_timeout,
      [&](const Bytes& b) {
        return static_cast<long>(replyLengthFromHeader(request.request(), b));
      },
      kShortestReply, kMaxAduLength, &reply, &error);
  if (status == ReadStatus::kComplete) return decodeReply(request, reply);
  return readFailure(request.request(), status, reply, error, medium);
}

void Link::account(const Result& r, double latency) {
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
void Link::countAttempt(const Result& r) {
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

void Link::addStaleBytes(uint64_t n) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.stale_bytes += n;
}

// The line discipline.
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
// its reply may still come, and a request of the same shape would take it: wait until the line
// has been quiet that long. A retry of that transaction need not wait: a late answer to it is
// the right answer. Nor need a new read with its frame: the late reply answers the same
// question, a little earlier, and nothing went to that slave in between (anything else waits
// here and settles the line); a silent device that a client reads again and again then costs
// each read its time-outs, not a guard more (issue 52). A new write waits even with the same
// frame: the old echo would confirm a write the device may never have heard (the simulation
// found a share client's FC05 confirmed by the echo of an earlier command's, stop 56). Another
// slave's request cannot take it (the address differs), so a dead device costs the others
// nothing.
void Link::settleLine(int fd, const EncodedRequest& request) {
  if (const auto until = guardUntil(request)) {
    awaitQuietLine(fd, *until);
    lineSettled(request);
  }
}

std::optional<std::chrono::steady_clock::time_point> Link::guardUntil(
    const EncodedRequest& request) {
  const auto now = lineNow();
  forgetSettled(now);
  const Unsettled* guard = holding(request, retrying_);
  if (!guard) {
    settled_at_ = now;
    return std::nullopt;
  }
  return guard->failed_at + seconds(config_.late_reply_guard);
}

const Link::Unsettled* Link::holding(const EncodedRequest& request, bool retry) const {
  const auto mine = unsettled_.find(request.request().slave);
  if (mine == unsettled_.end()) return nullptr;
  const bool takes_it =
      mine->second.frame == request.adu() && (retry || isReadFunction(request.request().function));
  return takes_it ? nullptr : &mine->second;
}

void Link::forgetSettled(std::chrono::steady_clock::time_point now) {
  const auto guard = seconds(config_.late_reply_guard);
  for (auto it = unsettled_.begin(); it != unsettled_.end();)
    it = now - it->second.failed_at >= guard ? unsettled_.erase(it) : std::next(it);
}

void Link::lineSettled(const EncodedRequest& request) {
  // The line was quiet: nothing late is on its way from this slave, nor from one whose guard
  // has run out; another's reply may still come later (its own guard is kept).
  unsettled_.erase(request.request().slave);
  settled_at_ = lineNow();  // the request goes after the wait: its own reply is due from here
  forgetSettled(settled_at_);
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
    // Bytes push the end back, never forward: noise early in the wait must not cut short the
    // guard a failed request's own late reply needs (the simulation found it: stop 56).
    until = std::max(until, Steady::now() + seconds(config_.late_reply_guard));
  }
  last_activity_ = Steady::now();
  guard_wait_ = last_activity_ - began;
  addStaleBytes(dropped);
}

}  // namespace modbus_rtu_driver
