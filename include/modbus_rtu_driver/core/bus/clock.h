// What the bus thread reads the time from and sleeps on. SteadyClock is the real one;
// ManualClock is for tests: its time moves only when someone advances it, and a test can see
// when the threads using it are asleep, so timing is exact and never waits for real time.
#pragma once

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <iterator>
#include <map>
#include <mutex>
#include <vector>

namespace modbus_rtu_driver {

class Clock {
 public:
  using time_point = std::chrono::steady_clock::time_point;
  using duration = std::chrono::steady_clock::duration;

  virtual ~Clock() = default;
  virtual time_point now() const = 0;
  // Waits on `cv` (with `lock` held, as condition_variable::wait does) until notified or until
  // now() reaches `deadline` (time_point::max() = no deadline). May return early: callers
  // re-check what they wait for.
  virtual void waitUntil(std::unique_lock<std::mutex>& lock, std::condition_variable& cv,
                         time_point deadline) = 0;
  // Wakes whoever waits on `cv` in waitUntil. Use it instead of cv.notify_all(), so a manual
  // clock knows they are no longer asleep.
  virtual void notifyAll(std::condition_variable& cv) { cv.notify_all(); }

  // The real steady clock, shared.
  static Clock& steady();
};

class SteadyClock : public Clock {
 public:
  time_point now() const override { return std::chrono::steady_clock::now(); }
  void waitUntil(std::unique_lock<std::mutex>& lock, std::condition_variable& cv,
                 time_point deadline) override {
    if (deadline == time_point::max()) {
      cv.wait(lock);
    } else {
      cv.wait_until(lock, deadline);
    }
  }
};

inline Clock& Clock::steady() {
  static SteadyClock clock;
  return clock;
}

// Time stands still until advance()/advanceTo(). A thread in waitUntil is "asleep" until its
// deadline is reached or its condition variable is notified through notifyAll();
// nextDeadline() and awaitSleepers() let a test wait until the bus thread is idle and then move
// time straight to when it wakes.
class ManualClock : public Clock {
 public:
  explicit ManualClock(time_point start = time_point(std::chrono::hours(1))) : now_(start) {}

  time_point now() const override {
    std::lock_guard<std::mutex> g(m_);
    return now_;
  }

  void waitUntil(std::unique_lock<std::mutex>& lock, std::condition_variable& cv,
                 time_point deadline) override {
    uint64_t id;
    {
      std::lock_guard<std::mutex> g(m_);
      if (now_ >= deadline) return;
      id = next_id_++;
      sleepers_[id] = Sleeper{lock.mutex(), &cv, deadline};
    }
    changed_.notify_all();
    // advance() takes `lock`'s mutex before notifying, so it cannot notify between the
    // registration above and this wait.
    cv.wait(lock);
    std::lock_guard<std::mutex> g(m_);
    sleepers_.erase(id);
  }

  void notifyAll(std::condition_variable& cv) override {
    {
      std::lock_guard<std::mutex> g(m_);
      for (auto it = sleepers_.begin(); it != sleepers_.end();)
        it = it->second.cv == &cv ? sleepers_.erase(it) : std::next(it);
    }
    cv.notify_all();
  }

  void advance(duration d) { advanceTo(now() + d); }

  // Moves time to `t` (never back) and wakes the sleepers whose deadline it reaches.
  void advanceTo(time_point t) {
    std::vector<Sleeper> woken;
    {
      std::lock_guard<std::mutex> g(m_);
      now_ = std::max(now_, t);
      for (auto it = sleepers_.begin(); it != sleepers_.end();) {
        if (it->second.deadline <= now_) {
          woken.push_back(it->second);
          it = sleepers_.erase(it);
        } else {
          ++it;
        }
      }
    }
    for (const Sleeper& s : woken) {
      { std::lock_guard<std::mutex> g(*s.mutex); }  // the sleeper is inside cv.wait now
      s.cv->notify_all();
    }
  }

  // The earliest deadline of the sleepers; time_point::max() when none has one.
  time_point nextDeadline() const {
    std::lock_guard<std::mutex> g(m_);
    time_point next = time_point::max();
    for (const auto& s : sleepers_) next = std::min(next, s.second.deadline);
    return next;
  }

  // Waits (in real time, at most `timeout`: a safety net) until `n` threads are asleep.
  bool awaitSleepers(size_t n, std::chrono::milliseconds timeout) const {
    std::unique_lock<std::mutex> g(m_);
    return changed_.wait_for(g, timeout, [&] { return sleepers_.size() >= n; });
  }

 private:
  struct Sleeper {
    std::mutex* mutex;
    std::condition_variable* cv;
    time_point deadline;
  };
  mutable std::mutex m_;
  mutable std::condition_variable changed_;
  time_point now_;
  std::map<uint64_t, Sleeper> sleepers_;
  uint64_t next_id_ = 0;
};

}  // namespace modbus_rtu_driver
