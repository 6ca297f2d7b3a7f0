// The parameter server's running_timed/<device> lists for the fail-safe's simulation: a map the
// harness owns, so that it outlives a killed or stopped node as roscore does, with the ends in
// the simulation's clock's seconds. The node writes them from a thread of its own
// (RunningTimedParameter), one write at a time, each taking `latency` s: a node killed before
// a list landed leaves the one before (a clean stop flushes them). ROS-free.
#pragma once

#include <chrono>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/runtime/kept_timed_store.h"

namespace modbus_rtu_driver {

class MemoryKeptTimed : public KeptTimedStore {
 public:
  explicit MemoryKeptTimed(Clock& clock) : clock_(clock) {}
  // s one parameter write takes (0: none: a list lands when it is kept).
  void setLatency(double seconds) { latency_ = seconds; }

  std::vector<KeptTimedCommand> read(const std::string& device) const override {
    land();
    const auto it = lists_.find(device);
    return it == lists_.end() ? std::vector<KeptTimedCommand>{} : it->second;
  }
  // As RunningTimedParameter's thread: a list kept while none is being written is written at
  // once (it lands `latency` s later); one kept during a write waits for it, and only the
  // newest waiting list is written next.
  void keep(const std::string& device, std::vector<KeptTimedCommand> kept) override {
    land();
    Writes& w = writes_[device];
    Write next{clock_.now(), clock_.now(), std::move(kept)};
    if (!w.in_flight) {
      next.lands = clock_.now() + latency();
      w.in_flight = std::move(next);
    } else {
      w.waiting = std::move(next);
    }
    land();
  }
  double seconds() const override {
    return std::chrono::duration<double>(clock_.now().time_since_epoch()).count();
  }
  // A clean stop: every list kept so far is written (RunningTimedParameter::flush).
  void flush() {
    for (auto& [device, w] : writes_) {
      if (w.in_flight) put(device, *w.in_flight);
      if (w.waiting) put(device, *w.waiting);
    }
    writes_.clear();
  }
  // A kill: what has not landed by now never will. Returns how many lists were lost.
  size_t dropPending() {
    land();
    size_t lost = 0;
    for (const auto& [device, w] : writes_) lost += (w.in_flight ? 1 : 0) + (w.waiting ? 1 : 0);
    writes_.clear();
    return lost;
  }
  // The lists as the next node would read them now.
  const std::map<std::string, std::vector<KeptTimedCommand>>& landed() const {
    land();
    return lists_;
  }
  // When the node kept the list that landed last for `device` (none landed: the epoch).
  Clock::time_point landedKeptAt(const std::string& device) const {
    land();
    const auto it = kept_at_.find(device);
    return it == kept_at_.end() ? Clock::time_point{} : it->second;
  }

 private:
  struct Write {
    Clock::time_point kept_at;
    Clock::time_point lands;
    std::vector<KeptTimedCommand> list;
  };
  struct Writes {
    std::optional<Write> in_flight;
    std::optional<Write> waiting;
  };
  Clock::duration latency() const {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(latency_));
  }
  void land() const {
    const Clock::time_point now = clock_.now();
    for (auto& [device, w] : writes_) {
      while (w.in_flight && w.in_flight->lands <= now) {
        const Clock::time_point done = w.in_flight->lands;
        put(device, *w.in_flight);
        w.in_flight.reset();
        if (w.waiting) {  // the thread writes the newest waiting list next
          w.in_flight = std::move(w.waiting);
          w.waiting.reset();
          w.in_flight->lands = done + latency();
        }
      }
    }
  }
  // Without a list, the key goes (as RunningTimedParameter deletes it).
  void put(const std::string& device, const Write& w) const {
    kept_at_[device] = w.kept_at;
    if (w.list.empty())
      lists_.erase(device);
    else
      lists_[device] = w.list;
  }

  Clock& clock_;
  double latency_ = 0;
  mutable std::map<std::string, Writes> writes_;
  mutable std::map<std::string, std::vector<KeptTimedCommand>> lists_;
  mutable std::map<std::string, Clock::time_point> kept_at_;
};

}  // namespace modbus_rtu_driver
