#include "modbus_rtu_driver/core/bus/bus_scheduler.h"

#include <pthread.h>

#include <algorithm>
#include <tuple>
#include <utility>

#include "modbus_rtu_driver/core/link/until_silent_transport.h"

namespace modbus_rtu_driver {

namespace {
Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

BusScheduler::BusScheduler(Transport& transport) : BusScheduler(transport, Options{}) {}

BusScheduler::BusScheduler(Transport& transport, Options options)
    : BusScheduler(transport, std::move(options), Clock::steady()) {}

BusScheduler::BusScheduler(Transport& transport, Options options, Clock& clock)
    : transport_(transport), options_(std::move(options)), clock_(clock), poll_transport_(*this) {}

BusScheduler::~BusScheduler() {
  stop();
}

void BusScheduler::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (running_) return;
  running_ = true;
  finished_ = false;
  next_connect_ = clock_.now();
  reconnect_delay_ = options_.reconnect_initial;
  thread_ = std::thread(&BusScheduler::run, this);
}

void BusScheduler::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    running_ = false;
  }
  clock_.notifyAll(wake_);
  if (thread_.joinable()) thread_.join();
  std::unique_lock<std::mutex> lock(mutex_);
  refuseQueued(lock, "bus stopped");
}

bool BusScheduler::stopBy(std::chrono::steady_clock::time_point deadline) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    running_ = false;
  }
  clock_.notifyAll(wake_);
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (thread_.joinable() && !finished_cv_.wait_until(lock, deadline, [&] { return finished_; }))
      return false;
  }
  stop();
  return true;
}

Result BusScheduler::NotingTransport::execute(const Request& request) {
  owner.useGuardTime(request);
  Result r =
      first == 0 && most < 0 ? inner.execute(request) : inner.executeAttempts(request, first, most);
  sent = true;
  last_unanswered = r.error == ErrorKind::kTimeout;
  return r;
}

Result BusScheduler::ClosedTransport::execute(const Request& /*request*/) {
  return Result::failure(ErrorKind::kNotConnected, reason);
}

void BusScheduler::Pending::finish(Result r) {
  if (done)
    done(r);
  else
    promise.set_value(std::move(r));
}

void BusScheduler::refuseQueued(std::unique_lock<std::mutex>& lock, const std::string& reason) {
  ClosedTransport closed;
  closed.reason = reason;
  // Writes first; both queues again after each job, as more may come while the lock is free.
  while (!writes_.empty() || !shared_.empty()) {
    std::deque<Pending>& queue = writes_.empty() ? shared_ : writes_;
    Pending p = std::move(queue.front());
    queue.pop_front();
    lock.unlock();
    Result r = p.job(closed);
    lock.lock();
    if (!r.ok() && !p.device.empty()) ++health_[p.device].writes_refused;
    lock.unlock();  // `done` may take its caller's locks
    p.finish(std::move(r));
    lock.lock();
  }
}

void BusScheduler::addDevice(const std::string& device) {
  std::lock_guard<std::mutex> lock(mutex_);
  health_[device];
}

void BusScheduler::addPoll(const std::string& device, double rate_hz, Job poll,
                           ResultCallback on_result) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    health_[device];
    if (!(rate_hz > 0)) return;  // 0 = never poll
    Poll p;
    p.device = device;
    p.period = seconds(1.0 / rate_hz);
    p.due = clock_.now();
    // At most 1 s: a device slower than that would let a fast one, catching up after a stall,
    // hold the others back for as long (up to the 3 s after which a schedule is given up).
    longest_period_ = std::min<Clock::duration>(std::max(longest_period_, p.period), seconds(1.0));
    p.job = std::move(poll);
    p.on_result = std::move(on_result);
    polls_.push_back(std::move(p));
  }
  clock_.notifyAll(wake_);  // the bus thread may be waiting with nothing to poll
}

BusScheduler::Job BusScheduler::tagged(Job job, uint64_t tag) {
  if (tag == 0) return job;
  return [this, tag, job = std::move(job)](Transport& t) {
    const uint64_t outer = current_tag_.exchange(tag, std::memory_order_relaxed);
    Result r = job(t);
    current_tag_.store(outer, std::memory_order_relaxed);
    return r;
  };
}

std::future<Result> BusScheduler::submit(const std::string& device, Job job, uint64_t tag) {
  Pending p;
  p.device = device;
  p.job = tagged(std::move(job), tag);
  std::future<Result> f = p.promise.get_future();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (running_) {
      writes_.push_back(std::move(p));
    } else {
      p.promise.set_value(Result::failure(ErrorKind::kIo, "bus stopped"));
    }
  }
  clock_.notifyAll(wake_);
  return f;
}

void BusScheduler::submitShared(const std::string& device, Job job, ResultCallback done,
                                uint64_t tag, std::optional<Request> request) {
  Result refused = Result::failure(ErrorKind::kIo, "bus stopped");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (shared_closed_) refused = Result::failure(ErrorKind::kNotConnected, shared_closed_reason_);
    if (running_ && !shared_closed_) {
      Pending p;
      p.device = device;
      p.job = tagged(std::move(job), tag);
      p.done = std::move(done);
      p.shared = true;
      p.request = std::move(request);
      shared_.push_back(std::move(p));
      done = nullptr;
    }
  }
  // Called outside the lock: the callback may submit again.
  if (done) {
    done(refused);
    return;
  }
  clock_.notifyAll(wake_);
}

void BusScheduler::closeShared(const std::string& reason) {
  std::deque<Pending> refused;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shared_closed_ = true;
    shared_closed_reason_ = reason;
    refused.swap(shared_);
  }
  // Outside the lock: `done` may take its caller's locks. Each job still runs exactly once,
  // against a transport that sends nothing.
  ClosedTransport closed;
  closed.reason = reason;
  for (Pending& p : refused) {
    Result r = p.job(closed);
    p.finish(std::move(r));
  }
}

void BusScheduler::openShared() {
  std::lock_guard<std::mutex> lock(mutex_);
  shared_closed_ = false;
}

DeviceHealth BusScheduler::health(const std::string& device) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = health_.find(device);
  return it == health_.end() ? DeviceHealth{} : it->second;
}

bool BusScheduler::online(const std::string& device) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = health_.find(device);
  return it == health_.end() || it->second.online;
}

size_t BusScheduler::queuedJobs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return writes_.size() + shared_.size();
}

uint64_t BusScheduler::ranInGuards() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return ran_in_guards_;
}

uint64_t BusScheduler::cutInGuards() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return cut_in_guards_;
}

bool BusScheduler::connected() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return connected_;
}

PortReopens BusScheduler::portReopens() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return reopens_;
}

std::string BusScheduler::connectionError() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return connection_error_;
}

void BusScheduler::record(const std::string& device, const Result& result, Kind kind) {
  if (result.error == ErrorKind::kInvalidArgument) return;  // never reached the bus
  if (device.empty()) return;                               // a shared request to nobody known
  const auto now = clock_.now();
  DeviceHealth& h = health_[device];
  if (kind == Kind::kShared) {
    (result.ok() ? h.shared_ok : h.shared_failed)++;
  } else if (kind == Kind::kPoll) {
    (result.ok() ? h.polls_ok : h.polls_failed)++;
    RateMeter& polls = poll_rates_[device];
    polls.record(now);
    h.achieved_poll_rate = polls.rate();
  } else {
    (result.ok() ? h.writes_ok : h.writes_failed)++;
  }
  if (!result.ok()) h.last_error = result.message;
  if (!noProperAnswer(result.error)) {  // it answered, even if with an exception
    h.answered = true;
    h.consecutive_failures = 0;
    if (!h.online)  // for the node's "back online after ..."
      h.last_offline_seconds = std::chrono::duration<double>(now - offline_since_[device]).count();
    h.online = true;
    backoff_.erase(device);
    backoff_until_.erase(device);
    return;
  }
  ++h.consecutive_failures;
  if (h.consecutive_failures < static_cast<uint32_t>(options_.offline_after)) return;
  if (h.online) offline_since_[device] = now;
  h.online = false;
  double& b = backoff_[device];
  b = b > 0 ? std::min(options_.backoff_max, b * 2) : options_.backoff_initial;
  backoff_until_[device] = now + seconds(b);
}

Clock::time_point BusScheduler::probeNotBefore(const Poll& poll) {
  auto b = backoff_until_.find(poll.device);
  if (b == backoff_until_.end() || health_[poll.device].online) return Clock::time_point{};
  return b->second;
}

// A silent device's poll costs a whole timeout with its retries: were it to go by lateness
// alone, a few silent devices with longer periods (each always a period late) would take the
// bus from a fast device that answers until their backoff had grown, and with it that device's
// restart detection and owed safe writes (docs/share.md). So it goes after the answering
// devices' due polls, each of which it then delays by one transaction at most, until it is
// offline (its probes then wait out the backoff instead); one that has waited the longest
// backoff goes in its turn, so a bus that cannot carry the answering devices' rates still
// probes it.
bool BusScheduler::yieldsToAnswering(const Poll& poll, Clock::time_point due,
                                     Clock::time_point now) const {
  if (unanswered_.count(poll.device) == 0) return false;
  // Once offline, its probes are spaced by the backoff already: each goes in its turn, so a
  // device that answers again is seen within the backoff, also on a busy bus.
  const auto h = health_.find(poll.device);
  if (h != health_.end() && !h->second.online) return false;
  return now - due < seconds(options_.backoff_max);
}

BusScheduler::Poll* BusScheduler::starvingPoll(Clock::time_point now) {
  if (last_ran_starving_poll_ || (writes_.empty() && shared_.empty())) return nullptr;
  // A device with a job of its own queued is left to it: its poll runs after (a poll between
  // would see the device before that write, and whatever it decides would be decided twice).
  auto queuedFor = [this](const std::string& device) {
    for (const auto* queue : {&writes_, &shared_})
      for (const Pending& job : *queue)
        if (job.device == device) return true;
    return false;
  };
  Poll* oldest = nullptr;
  for (Poll& p : polls_) {
    if (p.due + p.period > now || queuedFor(p.device) || probeNotBefore(p) > now) continue;
    // Starved by the queued jobs only when they have held the line a whole period of it (no
    // poll ran since): on a bus the polls alone fill, every poll is a period late and it
    // waits its turn among them; a queued request going first there costs it one transaction.
    // Without this, each client's read waited for a poll (issue 52: a shared read 2.5 ms
    // later at p50 under the soak, where the polls ran as often without it).
    if (now - last_poll_end_ < p.period) continue;
    if (!oldest || std::make_pair(yieldsToAnswering(p, p.due, now), p.due) <
                       std::make_pair(yieldsToAnswering(*oldest, oldest->due, now), oldest->due))
      oldest = &p;
  }
  return oldest;
}

bool BusScheduler::runOneQueued(std::unique_lock<std::mutex>& lock) {
  std::deque<Pending>& queue = writes_.empty() ? shared_ : writes_;
  if (queue.empty()) return false;
  Pending p = std::move(queue.front());
  queue.pop_front();
  runPending(lock, std::move(p));
  return true;
}

void BusScheduler::runPending(std::unique_lock<std::mutex>& lock, Pending p, int most) {
  const bool was_unanswered = unanswered_.count(p.device) > 0;
  lock.unlock();
  NotingTransport noted(transport_, *this);
  noted.first = p.attempts_done;
  noted.most = most;
  UntilSilentTransport until_silent(noted);
  Result r = p.job(was_unanswered ? static_cast<Transport&>(until_silent) : noted);
  lock.lock();
  if (noted.sent && !p.device.empty()) {
    if (noted.last_unanswered)
      unanswered_.insert(p.device);
    else
      unanswered_.erase(p.device);
  }
  if (r.retry_owed && p.shared && most > 0) {
    // Its answer lost in the attempts that fitted: the rest after the guarded request, first of
    // the shared ones (its job was told and answers the client if they cannot come in time).
    p.attempts_done += most;
    ++cut_in_guards_;
    shared_.push_front(std::move(p));
    return;
  }
  record(p.device, r, p.shared ? Kind::kShared : Kind::kWrite);
  if (r.error == ErrorKind::kIo) transport_.disconnect();
  lock.unlock();  // `done` may take its caller's locks
  p.finish(std::move(r));
  lock.lock();
}

// A guard holds only its own slave's next request (another slave's reply has another address:
// it cannot be taken for it), so the line is free for others meanwhile. Only shared requests
// use it, each with a known longest attempt, and only the attempts that end before the guard
// does: the guarded request starts no later than it would have, and the writes and polls keep
// their order. A read whose answer those attempts lost gets its remaining retries after the
// guarded request (runPending). Without this, a device whose replies are dropped held every
// client's read of another device for its guards (about 145 ms after each retry: issue 52).
// Attempts, not whole transactions: a read's two attempts (up to about 105 ms at 115200 with
// the default timeouts) fitted only a guard's first 40 ms or so.
void BusScheduler::useGuardTime(const Request& next) {
  if (in_guard_) return;
  while (transport_.connected()) {
    const double left = transport_.guardLeft(next);
    if (left <= 0) return;
    std::unique_lock<std::mutex> lock(mutex_);
    const auto it = fitsInGuard(next.slave, left);
    if (it == shared_.end()) return;
    Pending p = std::move(*it);
    shared_.erase(it);
    // As many attempts as end before the guard does (fitsInGuard: at least one).
    const int most = std::max(1, static_cast<int>(left / transport_.attemptSeconds(*p.request)));
    ++ran_in_guards_;
    in_guard_ = true;
    runPending(lock, std::move(p), most);
    in_guard_ = false;
    lock.unlock();
    if (guard_observer_) guard_observer_(next.slave, left, transport_.guardLeft(next));
  }
}

std::deque<BusScheduler::Pending>::iterator BusScheduler::fitsInGuard(uint8_t guarded,
                                                                      double left) {
  std::set<uint8_t> passed;  // slaves with an earlier shared request: theirs go in order
  for (auto it = shared_.begin(); it != shared_.end(); ++it) {
    // Checked and read through one name: clang-tidy 19 does not follow a check through `it->`.
    const std::optional<Request>& shared = it->request;
    if (!shared) continue;
    const Request& request = *shared;
    const uint8_t slave = request.slave;
    if (!passed.insert(slave).second || slave == guarded || slave == kBroadcastAddress) continue;
    // A ROS write queued for that device goes before it, as it would have.
    const std::string owner = "slave " + std::to_string(slave);
    const bool write_queued = std::any_of(writes_.begin(), writes_.end(), [&](const Pending& w) {
      return w.device == owner || (!it->device.empty() && w.device == it->device);
    });
    if (write_queued || transport_.guardLeft(request) > 0) continue;
    const double attempt = transport_.attemptSeconds(request);
    if (attempt > 0 && attempt <= left) return it;
  }
  return shared_.end();
}

// A poll of several transactions lets queued writes and shared requests go first before each of
// them, so they wait for at most one transaction, not a whole poll.
Result BusScheduler::PollTransport::execute(const Request& request) {
  owner.transport_.awaitLineFree();  // a write that comes during the gap still goes first
  {
    std::unique_lock<std::mutex> lock(owner.mutex_);
    // A poll that went before them sends its first request first, then lets one queued job go
    // before each of its later ones, not the whole queue (docs/share.md: it goes before the
    // next queued one, which then gets one transaction of it each).
    if (owner.starving_poll_running_) {
      if (owner.starving_poll_sent_ && owner.transport_.connected()) owner.runOneQueued(lock);
      owner.starving_poll_sent_ = true;
    } else {
      while (owner.transport_.connected() && owner.runOneQueued(lock)) {
      }
    }
  }
  owner.useGuardTime(request);
  return owner.transport_.execute(request);
}

void BusScheduler::run() {
  // Named, so top -H, perf and the benchmark tell the bus thread's CPU from ROS's threads.
  pthread_setname_np(pthread_self(), "modbus_bus");
  if (options_.on_thread_start) options_.on_thread_start();
  std::unique_lock<std::mutex> lock(mutex_);
  while (running_) {
    Clock::time_point wait{};
    if (stepLocked(lock, &wait)) continue;
    if (!running_) break;  // the lock was free while jobs ran: stop() may have come then
    clock_.waitUntil(lock, wake_, wait);
  }
  finished_ = true;
  finished_cv_.notify_all();
}

void BusScheduler::startStepping() {
  std::lock_guard<std::mutex> lock(mutex_);
  running_ = true;
  finished_ = true;  // no thread: stopBy() has nothing to wait for
  next_connect_ = clock_.now();
  reconnect_delay_ = options_.reconnect_initial;
}

bool BusScheduler::step(Clock::time_point* next) {
  std::unique_lock<std::mutex> lock(mutex_);
  Clock::time_point wait = Clock::time_point::max();
  const bool ran = running_ && stepLocked(lock, &wait);
  if (next) *next = running_ ? wait : Clock::time_point::max();
  return ran;
}

bool BusScheduler::stepLocked(std::unique_lock<std::mutex>& lock, Clock::time_point* wait) {
  auto now = clock_.now();
  if (!transport_.connected()) {
    if (connected_ && !port_lost_at_) port_lost_at_ = now;  // it dropped while open
    if (now >= next_connect_) {
      lock.unlock();
      std::string error;
      const bool ok = transport_.connect(&error);
      lock.lock();
      // Never retry faster than the initial delay, even if a transport misreports itself.
      next_connect_ = clock_.now() + seconds(options_.reconnect_initial);
      connected_ = ok;
      connection_error_ = ok ? "" : error;
      if (ok) {
        reconnect_delay_ = options_.reconnect_initial;
        if (port_lost_at_) {  // for the node's "port open again after ..."
          ++reopens_.count;
          reopens_.last_outage_seconds =
              std::chrono::duration<double>(clock_.now() - *port_lost_at_).count();
          port_lost_at_.reset();
        }
        return true;
      }
      if (!port_lost_at_) port_lost_at_ = now;
      next_connect_ = clock_.now() + seconds(reconnect_delay_);
      reconnect_delay_ = std::min(options_.reconnect_max, reconnect_delay_ * 2);
    }
    // Nobody waits for a bus that is not there: queued writes fail now, and what they took
    // from shared queues fails with them (never sent later).
    refuseQueued(lock, "port not open: " + connection_error_);
    *wait = next_connect_;
    return false;
  }
  connected_ = true;

  Poll* next = starvingPoll(now);
  if (!next && runOneQueued(lock)) {  // writes, then shared requests, go ahead of polls
    last_ran_starving_poll_ = false;
    return true;
  }

  // The poll due first; an offline device waits out its backoff, and a silent device's due
  // poll waits for the answering devices' (yieldsToAnswering).
  Clock::time_point when = now;
  bool yields = false;
  const bool starving = next != nullptr;
  for (Poll& p : polls_) {
    if (starving) break;
    // A late device claims priority by how late it is, up to the longest period on the bus:
    // it catches up after a stall without holding the others back longer than that, and on a
    // bus that cannot carry the rates every device a whole longest period late has the same
    // claim, so they go in turn. (A cap at the device's own period gave the slow devices the
    // larger claim: a fast device, always less late than they, went unpolled.)
    const auto due = std::max(p.due, probeNotBefore(p));
    const auto t = std::max(due, now - longest_period_);
    const bool y = t <= now && yieldsToAnswering(p, due, now);
    // Ties (devices late on a bus that cannot carry their rates) go to the one served least
    // recently, so an overloaded bus is shared in turn rather than by list order or by who
    // was reset last.
    const auto rank = std::make_tuple(t > now, y, t);
    const auto best = std::make_tuple(when > now, yields, when);
    if (!next || rank < best || (rank == best && p.last_run < next->last_run)) {
      next = &p;
      when = t;
      yields = y;
    }
  }
  if (!next) {
    *wait = Clock::time_point::max();
    return false;
  }
  if (when > now) {
    *wait = when;
    return false;
  }
  starving_poll_running_ = starving;
  starving_poll_sent_ = false;
  last_ran_starving_poll_ = starving;
  lock.unlock();
  Result r = next->job(poll_transport_);
  if (next->on_result) next->on_result(r);
  lock.lock();
  starving_poll_running_ = false;
  record(next->device, r, Kind::kPoll);
  // A poll stops at its first request that fails: its outcome is its last request's (a port
  // that failed says nothing of the device).
  if (r.error == ErrorKind::kTimeout)
    unanswered_.insert(next->device);
  else if (r.error != ErrorKind::kIo && r.error != ErrorKind::kNotConnected)
    unanswered_.erase(next->device);
  if (r.error == ErrorKind::kIo) transport_.disconnect();
  // Keep the schedule, so a poll delayed by a slow transaction (an offline device's probe)
  // is caught up and the average rate holds. Lagging more than 1 s means the bus cannot carry
  // the rate: say so; past 3 s give up catching up.
  now = clock_.now();
  next->last_run = now;
  last_poll_end_ = now;
  next->due += next->period;
  DeviceHealth& h = health_[next->device];
  const auto lag = now - next->due;
  h.rate_overrun = h.online && lag > std::chrono::seconds(1);
  if (lag > std::chrono::seconds(3)) next->due = now;
  return true;
}

}  // namespace modbus_rtu_driver
