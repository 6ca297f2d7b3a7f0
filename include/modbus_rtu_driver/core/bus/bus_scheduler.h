// The bus thread. It alone calls the Transport (and so libmodbus); everyone else hands it jobs.
// Three priorities: writes (submit) first, then shared requests (submitShared: Modbus TCP
// clients of the node's share), then polls; polls run at their device's rate, earliest due
// first, and a device that stops answering is polled with backoff so it cannot stall the others.
// Writes cannot stop the polls: a poll overdue by a whole period, when no poll has ended for that
// period, goes before the next queued job (unless its device has one queued), one such poll
// between two jobs (state topics, restart
// detection and owed safe writes all wait for polls; a queued write waits at most that one poll).
// Time comes from a Clock (the real steady clock unless one is given; tests use a ManualClock).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/bus/rate_meter.h"
#include "modbus_rtu_driver/core/link/transport.h"

namespace modbus_rtu_driver {

// A job's outcome known without running it (nothing to write, a request refused unsent), in the
// form BusScheduler::submit answers.
inline std::future<Result> readyResult(Result r) {
  std::promise<Result> p;
  p.set_value(std::move(r));
  return p.get_future();
}

struct DeviceHealth {
  bool online = true;     // false after `offline_after` failed transactions in a row
  bool answered = false;  // it has answered at least once (online in /diagnostics only then)
  uint32_t consecutive_failures = 0;
  uint64_t polls_ok = 0, polls_failed = 0, writes_ok = 0, writes_failed = 0;
  uint64_t writes_refused = 0;  // failed unsent: the port was not open or the bus stopped
  uint64_t shared_ok = 0, shared_failed = 0;  // requests of Modbus TCP clients (submitShared)
  std::string last_error;                     // empty when none yet
  double achieved_poll_rate = 0;              // Hz over the last seconds
  bool rate_overrun = false;                  // the bus could not keep the configured rate
  double last_offline_seconds = 0;            // how long its last offline spell lasted
};

// The port's losses: how often it opened again after failing or dropping, and after how long.
struct PortReopens {
  uint64_t count = 0;
  double last_outage_seconds = 0;
};

class BusScheduler {
 public:
  using Job = std::function<Result(Transport&)>;
  using ResultCallback = std::function<void(const Result&)>;

  struct Options {
    int offline_after = 3;           // failed transactions in a row before a device is offline
    double backoff_initial = 0.5;    // s between probes of an offline device, doubling
    double backoff_max = 5.0;        // s
    double reconnect_initial = 0.5;  // s between attempts to reopen the port, doubling
    double reconnect_max = 5.0;      // s
    // Runs first on the bus thread (the node raises the thread's priority there).
    std::function<void()> on_thread_start;
  };

  explicit BusScheduler(Transport& transport);
  BusScheduler(Transport& transport, Options options);
  // Reads the time from and sleeps on `clock` (the real steady clock otherwise); it must outlive
  // the scheduler.
  BusScheduler(Transport& transport, Options options, Clock& clock);
  ~BusScheduler();  // stops the thread; pending jobs fail with "bus stopped"

  void start();
  // Step mode, for a deterministic simulation: the scheduler takes jobs as after start(), but
  // runs no thread; the caller runs the bus with step(), one unit of work at a time, on its own
  // thread. stop() ends it as it ends the thread.
  void startStepping();
  // Runs the one thing the bus thread would run now (an attempt to open the port, the oldest
  // queued job, or the poll due first) and returns true; or returns false with `next` set to
  // when something falls due (time_point::max(): nothing until a job is queued). Without a
  // port, queued jobs are refused as the thread refuses them.
  bool step(Clock::time_point* next);
  void stop();
  // stop(), but waits for the job in progress (a transaction to a silent device may take
  // response_timeout x (retries + 1)) only until `deadline` (real time). False when the thread
  // is still in that job: it keeps running, so the scheduler must not be destroyed (the node
  // then ends the process).
  bool stopBy(std::chrono::steady_clock::time_point deadline);

  // Registers a device so its health is tracked.
  void addDevice(const std::string& device);
  // Periodic poll of `device` at `rate_hz` (0 = never). `on_result` runs on the bus thread right
  // after each poll with its outcome. May be called while the bus runs (the node starts polling
  // only once the start-up safe states are written).
  void addPoll(const std::string& device, double rate_hz, Job poll, ResultCallback on_result);

  // Runs `job` on the bus thread ahead of every poll. The future holds the real outcome. When
  // the device is offline the job still runs once (a write is how a user probes too), but the
  // transport's retries are what they are: the answer comes after one attempt cycle.
  // Every submitted job runs exactly once: while the port is not open (or once the bus stops)
  // it runs against a transport that refuses every request, so a job that took requests from a
  // shared queue (merged writes, command topics) fails them all and keeps nothing for later.
  // `tag` names the caller's operation: currentTag() says it while the job runs (0: none).
  std::future<Result> submit(const std::string& device, Job job, uint64_t tag = 0);
  // Runs `job` on the bus thread after every queued write and ahead of every poll (a shared
  // request from a Modbus TCP client), with submit's guarantees: it runs exactly once, against
  // the refusing transport while the port is not open or once the bus stops. `done` gets the
  // outcome exactly once: on the bus thread, or on the caller's when the bus is not running.
  // An empty `device` (a slave address no configured device has) keeps no health. `request`:
  // the job's one request, when it has one; such a job may go while another slave's late-reply
  // guard holds the line, if it ends before that guard does (docs/share.md).
  void submitShared(const std::string& device, Job job, ResultCallback done, uint64_t tag = 0,
                    std::optional<Request> request = std::nullopt);
  // Bus thread: the tag of the submitted job running now (0: a poll, or a job given none), for
  // a trace of whose request is on the line (the fail-safe's simulation tells its callers'
  // writes from the fail-safe's own by it).
  uint64_t currentTag() const { return current_tag_.load(std::memory_order_relaxed); }
  // Stops taking shared requests: those queued now and every later one fail unsent with
  // `reason` (kNotConnected), the one on the bus right now finishes. The node calls it before
  // its safe writes at shutdown, so no client's request runs after them. openShared() undoes it.
  void closeShared(const std::string& reason);
  void openShared();

  DeviceHealth health(const std::string& device) const;
  // health(device).online without copying the rest (its last error's text): after every poll.
  bool online(const std::string& device) const;
  // Jobs queued and not yet running (writes and shared requests).
  size_t queuedJobs() const;
  // Shared requests run while another slave's late-reply guard held the line (docs/share.md).
  uint64_t ranInGuards() const;
  // Of those, reads whose answer was lost in the attempts that fitted: their retries went after
  // the guarded request.
  uint64_t cutInGuards() const;
  // Called on the bus thread after each: the guarded slave, and the seconds its guard had left
  // before and after (the simulation checks that it ended first: after > 0). Set before start.
  using GuardTimeObserver = std::function<void(uint8_t slave, double before, double after)>;
  void setGuardTimeObserver(GuardTimeObserver observer) { guard_observer_ = std::move(observer); }
  bool connected() const;
  std::string connectionError() const;
  PortReopens portReopens() const;

 private:
  struct Poll {
    std::string device;
    Clock::duration period{};
    Clock::time_point due{};
    Clock::time_point last_run{};  // when it was last polled
    Job job;
    ResultCallback on_result;
  };
  struct Pending {
    std::string device;
    Job job;
    std::promise<Result> promise;
    ResultCallback done;  // set instead of the promise for shared requests
    bool shared = false;
    std::optional<Request> request;  // a shared job's one request (submitShared)
    int attempts_done = 0;           // of that request, run in another slave's guard (useGuardTime)
    void finish(Result r);
  };

  // What poll jobs see: the transport, with queued writes run before each transaction.
  struct PollTransport : Transport {
    explicit PollTransport(BusScheduler& scheduler) : owner(scheduler) {}
    Result execute(const Request& request) override;
    bool connect(std::string* error) override { return owner.transport_.connect(error); }
    bool connected() const override { return owner.transport_.connected(); }
    void disconnect() override { owner.transport_.disconnect(); }
    BusScheduler& owner;
  };

  // What a queued job sees: the link, noting whether the job's last request got no reply at
  // all (every retry timed out). A shared read run in another slave's guard runs attempts
  // `first` on, at most `most` of them (< 0: all its retries).
  struct NotingTransport : Transport {
    NotingTransport(Transport& link, BusScheduler& scheduler) : inner(link), owner(scheduler) {}
    Result execute(const Request& request) override;
    bool connected() const override { return inner.connected(); }
    void awaitLineFree() override { inner.awaitLineFree(); }
    Transport& inner;
    BusScheduler& owner;
    int first = 0, most = -1;
    bool sent = false;
    bool last_unanswered = false;
  };

  // What jobs see while the port is not open: every request fails with `reason`, unsent.
  struct ClosedTransport : Transport {
    Result execute(const Request& request) override;
    bool connected() const override { return false; }
    std::string reason;
  };

  // `job`, with currentTag() saying `tag` while it runs (nested: a poll runs queued writes).
  Job tagged(Job job, uint64_t tag);
  void run();
  // One pass of the bus thread's loop (`lock` held on entry and on return): true when it ran
  // something, else false with `wait` = when to look again.
  bool stepLocked(std::unique_lock<std::mutex>& lock, Clock::time_point* wait);
  // Runs the oldest write, else the oldest shared request; `lock` held on entry and on return.
  bool runOneQueued(std::unique_lock<std::mutex>& lock);
  // Runs `p` (taken off its queue); `lock` held on entry and on return. `most`: at most that
  // many attempts of a shared request (< 0: all); a read whose answer they lost goes back to the
  // head of the shared queue for its remaining retries.
  void runPending(std::unique_lock<std::mutex>& lock, Pending p, int most = -1);
  // Before `next` (lock free): while its slave's late-reply guard holds it, runs the queued shared
  // requests to other slaves, each attempt ending before the guard does.
  void useGuardTime(const Request& next);
  // The first shared request one attempt of which can go within `left` seconds of `guarded`'s
  // guard (a request to another slave, not guarded itself, with no earlier request of its slave
  // or write of its device queued); shared_.end() if none. `lock` held.
  std::deque<Pending>::iterator fitsInGuard(uint8_t guarded, double left);
  // The poll overdue by a whole period the longest, while no poll has ended for that period
  // (none while the last thing run was such a poll, or nothing is queued): it goes before the
  // queued jobs. `lock` held.
  Poll* starvingPoll(Clock::time_point now);
  // An offline device's poll waits out its backoff: not before then (else the epoch). `lock` held.
  Clock::time_point probeNotBefore(const Poll& poll);
  // A poll of a device whose last request got no reply, due since `due`: it waits for the due
  // polls of devices that answer, unless it has waited `backoff_max` already. `lock` held.
  bool yieldsToAnswering(const Poll& poll, Clock::time_point due, Clock::time_point now) const;
  // Runs every queued job against a ClosedTransport saying `reason`; `lock` held on entry/exit.
  void refuseQueued(std::unique_lock<std::mutex>& lock, const std::string& reason);
  enum class Kind { kPoll, kWrite, kShared };
  void record(const std::string& device, const Result& result, Kind kind);

  Transport& transport_;
  Options options_;
  Clock& clock_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Pending> writes_;
  std::deque<Pending> shared_;
  std::deque<Poll> polls_;  // a deque: adding a poll keeps the one running valid
  Clock::duration
      longest_period_{};  // of polls_, at most 1 s: the most priority a late poll claims
  std::map<std::string, DeviceHealth> health_;
  std::map<std::string, Clock::time_point> backoff_until_;
  std::map<std::string, double> backoff_;
  std::map<std::string, RateMeter> poll_rates_;
  PollTransport poll_transport_;
  bool starving_poll_running_ = false;  // a poll that went before queued jobs: runs them 1:1
  bool starving_poll_sent_ = false;     // its first request went: queued jobs may go between
  bool last_ran_starving_poll_ = false;
  Clock::time_point last_poll_end_{};  // when the last poll ended (starvingPoll)
  bool running_ = false;
  bool finished_ = false;                // run() has returned
  std::condition_variable finished_cv_;  // real time, not clock_: stopBy's bound is wall time
  bool shared_closed_ = false;
  std::string shared_closed_reason_;
  bool connected_ = false;
  std::string connection_error_;
  std::optional<Clock::time_point> port_lost_at_;
  Clock::time_point next_connect_{};  // the next attempt to open the port
  double reconnect_delay_ =
      0;  // s, doubling up to reconnect_max  // set while the port is lost (or never opened)
  PortReopens reopens_;
  std::map<std::string, Clock::time_point> offline_since_;
  // Devices whose last request got no reply at all: a job for one stops at its first request
  // that again gets none (docs/failsafe.md "Timing": one transaction per job, not a write and
  // then its read back, each with every retry).
  std::set<std::string> unanswered_;
  std::atomic<uint64_t> current_tag_{0};
  bool in_guard_ = false;  // bus thread: a job useGuardTime runs (its requests fill nothing)
  uint64_t ran_in_guards_ = 0;
  uint64_t cut_in_guards_ = 0;  // shared reads whose retries went after the guarded request
  GuardTimeObserver guard_observer_;
  std::thread thread_;
};

}  // namespace modbus_rtu_driver
