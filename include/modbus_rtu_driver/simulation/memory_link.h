// The deterministic simulation's line (ROS-free): a real Link (its retry rule, its encoding and
// its reply checks) whose medium is the simulator's device models in the same process. Every
// frame goes to the models byte for byte and their reply comes back byte for byte; time is a
// ManualClock that each frame moves on by its time on the wire (or by the response timeout when
// nothing answers), so the same calls give the same frames at the same times. Replies arrive in
// the line's input at their time: a request's reply is the first frame that arrives within its
// response timeout, whoever sent it, and what arrived before the request went out is thrown
// away (RtuLink's flush); the link's late-reply guard (Link::guardUntil) is waited out on this
// clock. Faults are set per device: silent, replies lost, late (after the timeout, when they may
// be read as a later request's), repeated, garbled, refused, foreign; and the port can be lost.
// Every frame is folded into a digest (FNV-1a) and kept in a short history for failure reports.
#pragma once

#include <cstdint>
#include <cstdio>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/link/link.h"
#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

// A frame on the line that is not the reply the node waits for, with a good CRC (IEC 61784-3's
// insertion, masquerade and addressing); the device acted on the request all the same.
enum class ForeignFrame {
  kInserted,    // an unsolicited frame: another master's read of another address
  kMasquerade,  // the reply claims another function code
  kAddressing,  // the reply comes from (claims) another address
};

struct MemoryLinkFaults {
  bool silent = false;     // hears nothing, answers nothing
  int lost = 0;            // the next N replies are lost (the device acted)
  int late = 0;            // the next N replies come after the response timeout (acted)
  double late_by = 0.001;  // s after the response timeout that they arrive
  // The next N replies arrive twice (IEC 61784-3's repetition: a repeater or gateway that sends
  // a frame again), the copy `repeat_after` s after the first ends (the device acted once).
  int repeated = 0;
  double repeat_after = 0;
  int garbled = 0;  // the next N replies arrive with a bad CRC (acted)
  // The next N requests are refused with exception `refused_code` (01, 02, 03, 04, 06): the
  // device answers and does nothing.
  int refused = 0;
  uint8_t refused_code = 0x04;
  // The next N replies are replaced by a foreign frame of `foreign_kind` (the device acted).
  int foreign = 0;
  ForeignFrame foreign_kind = ForeignFrame::kInserted;
};

// What one attempt did, for the invariants: the request as the device decoded it, whether the
// device heard it (and so acted on a write) and whether its normal reply reached the node.
struct LineEvent {
  Request request;
  bool heard = false;
  bool answered = false;     // a reply the node could decode (a normal one or an exception)
  bool refused = false;      // an exception the fault injected, read: the device did nothing
  bool port_failed = false;  // the port failed with this request out (heard, no reply)
  // The frame the node read was not this request's reply: a late or repeated reply to an
  // earlier request (incorrect sequence, repetition), or a foreign frame. `answered` says
  // whether the node took it.
  bool stale = false;
  // A late reply taken as another request's reply though it came within late_reply_guard of
  // its own request's time-out (the guard's promise broken: I21).
  bool taken_within_guard = false;
  // A late reply within late_reply_guard taken by a new read with its request's frame, as a
  // retry would take it (F90 lets it: the same question, answered a little earlier).
  bool taken_by_same_read = false;
  std::vector<uint16_t> values;  // a read's answer as the node got it (the device's state
                                 // at the request, not at the observer's later clock)
  uint64_t execute_id = 0;
  Clock::time_point at{};
};

class MemoryLink : public Link {
 public:
  MemoryLink(LinkConfig config, ManualClock& clock);

  void addDevice(std::unique_ptr<SimDevice> device);
  SimDevice* device(uint8_t address);
  MemoryLinkFaults& faults(uint8_t address) { return faults_[address]; }
  // Every device's faults, and a port failure armed for the next frame (not the port's state).
  void clearFaults();

  // The port: lost (every attempt fails with an i/o error, connect fails) or back.
  void setPortLost(bool lost);
  // The port fails during the next attempt, after its request went out (the device hears it and
  // acts; the node gets an i/o error and no reply), and stays lost.
  void failPortAfterNextFrame() { fail_after_frame_ = true; }
  void clearPortFailure() { fail_after_frame_ = false; }  // one armed and not yet used
  bool portLost() const { return port_lost_; }

  // Called after each attempt the line carried (not for a closed port).
  void onAttempt(std::function<void(const LineEvent&)> observer) {
    observer_ = std::move(observer);
  }
  // Transport::execute of the caller (one transaction, its retries included); the simulation
  // numbers them so that a frame sent twice for one transaction can be told apart from the same
  // command given twice.
  void beginTransaction() { ++execute_id_; }

  uint64_t digest() const { return digest_; }
  uint64_t frames() const { return frames_; }
  // The newest frames, oldest first: "t=12.345 tx 01 05 00 02 FF 00 ..".
  std::vector<std::string> history() const { return {history_.begin(), history_.end()}; }
  void keepHistory(size_t n) { history_size_ = n; }
  // Every frame also to `out` as it goes (nullptr: not).
  void trace(std::FILE* out) { trace_ = out; }

  // Transport
  bool connect(std::string* error) override;
  bool connected() const override { return connected_; }
  void disconnect() override { connected_ = false; }
  void awaitLineFree() override {}
  // Frames read as a request's reply that were another's, and frames thrown away unread.
  uint64_t staleRead() const { return stale_read_; }
  uint64_t staleDropped() const { return stale_dropped_; }

 protected:
  Result attempt(const EncodedRequest& request) override;
  Result sendBroadcast(const EncodedRequest& request) override;
  double minGap() const override { return 0.0; }
  Clock::time_point lineNow() const override { return clock_.now(); }

 private:
  // A frame on its way to the node: when its first byte arrives, and whose reply it is (the
  // attempt it answers; 0: none, a foreign frame).
  struct Arrival {
    Clock::time_point at;
    Bytes frame;
    uint64_t answers = 0;
    Bytes request;       // the request it answers
    double late_by = 0;  // s after that request's time-out (0: not late)
  };
  void fold(bool outgoing, const Bytes& frame);
  void wire(size_t bytes);  // moves time on by `bytes` characters plus the gap after them
  Clock::duration onWire(size_t bytes) const;
  void deliver(Clock::time_point at, Bytes frame, uint64_t answers, const Bytes& request = {},
               double late_by = 0);
  // The late-reply guard's wait (Link::awaitQuietLine on this line): frames that arrive before
  // `until` are dropped, each pushing it back by the guard, for 1 s at most.
  void awaitQuiet(Clock::time_point until);
  void dropInput(Clock::time_point up_to);  // what has arrived by then: thrown away unread
  // The first frame to arrive within the request's response timeout, read and decoded.
  Result readReply(const EncodedRequest& request, LineEvent& event, const char* no_reply);

  ManualClock& clock_;
  std::vector<std::unique_ptr<SimDevice>> devices_;
  MemoryLinkFaults faults_[256];
  bool port_lost_ = false;
  bool fail_after_frame_ = false;
  bool connected_ = false;
  double char_time_;
  std::function<void(const LineEvent&)> observer_;
  uint64_t execute_id_ = 0;
  uint64_t attempt_id_ = 0;
  std::deque<Arrival> input_;  // by arrival time
  uint64_t stale_read_ = 0;
  uint64_t stale_dropped_ = 0;
  uint64_t digest_ = 1469598103934665603ull;
  uint64_t frames_ = 0;
  std::deque<std::string> history_;
  size_t history_size_ = 40;
  std::FILE* trace_ = nullptr;
};

// What the bus runs its transactions through: numbers each transaction on the line (see
// MemoryLink::beginTransaction), then lets the link run it.
class CountingTransport : public Transport {
 public:
  explicit CountingTransport(MemoryLink& link) : link_(link) {}
  Result execute(const Request& request) override {
    link_.beginTransaction();
    return link_.execute(request);
  }
  // A transaction's later part (first > 0) is the same transaction: no new number.
  Result executeAttempts(const Request& request, int first, int most) override {
    if (first == 0) link_.beginTransaction();
    return link_.executeAttempts(request, first, most);
  }
  bool connect(std::string* error) override { return link_.connect(error); }
  bool connected() const override { return link_.connected(); }
  void disconnect() override { link_.disconnect(); }
  double guardLeft(const Request& next) const override { return link_.guardLeft(next); }
  double lineSeconds(const Request& request) const override { return link_.lineSeconds(request); }
  double attemptSeconds(const Request& request) const override {
    return link_.attemptSeconds(request);
  }

 private:
  MemoryLink& link_;
};

}  // namespace modbus_rtu_driver
