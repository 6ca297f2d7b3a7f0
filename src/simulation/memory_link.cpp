#include "modbus_rtu_driver/simulation/memory_link.h"

#include <algorithm>
#include <cstdio>

namespace modbus_rtu_driver {

namespace {
Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}
}  // namespace

MemoryLink::MemoryLink(LinkConfig config, ManualClock& clock)
    : Link(std::move(config)), clock_(clock) {
  // 8N1 (or the configured parity): start, data, parity, stop bits per character.
  const int bits =
      1 + config_.data_bits + (config_.parity == Parity::kNone ? 0 : 1) + config_.stop_bits;
  char_time_ = static_cast<double>(bits) / config_.baud;
}

void MemoryLink::addDevice(std::unique_ptr<SimDevice> device) {
  devices_.push_back(std::move(device));
}

SimDevice* MemoryLink::device(uint8_t address) {
  for (auto& d : devices_)
    if (d->address() == address) return d.get();
  return nullptr;
}

void MemoryLink::clearFaults() {
  for (auto& f : faults_) f = MemoryLinkFaults{};
  fail_after_frame_ = false;
}

void MemoryLink::setPortLost(bool lost) {
  port_lost_ = lost;
  if (lost) connected_ = false;
}

bool MemoryLink::connect(std::string* error) {
  if (port_lost_) {
    if (error) *error = "the adapter is gone (simulated port loss)";
    return false;
  }
  connected_ = true;
  input_.clear();  // a port opened again starts with nothing in its input
  noteConnected();
  return true;
}

void MemoryLink::wire(size_t bytes) {
  // The frame's characters, then the 3.5 characters of silence that end it.
  clock_.advance(seconds((static_cast<double>(bytes) + 3.5) * char_time_));
}

void MemoryLink::fold(bool outgoing, const Bytes& frame) {
  // FNV-1a over the direction, the time (ns) and the bytes: the same run gives the same digest.
  auto mix = [this](uint8_t b) {
    digest_ ^= b;
    digest_ *= 1099511628211ull;
  };
  mix(outgoing ? 0x54 : 0x52);
  const auto ns = static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(clock_.now().time_since_epoch())
          .count());
  for (int i = 0; i < 8; ++i) mix(static_cast<uint8_t>(ns >> (8 * i)));
  for (uint8_t b : frame) mix(b);
  ++frames_;
  if (history_size_ == 0 && !trace_) return;
  char when[32];
  std::snprintf(when, sizeof when, "t=%.3f ", static_cast<double>(ns) * 1e-9 - 3600.0);
  history_.push_back(std::string(when) + (outgoing ? "tx " : "rx ") + toHex(frame));
  if (trace_) std::fprintf(trace_, "%s\n", history_.back().c_str());
  while (history_.size() > history_size_) history_.pop_front();
}

Clock::duration MemoryLink::onWire(size_t bytes) const {
  return seconds(static_cast<double>(bytes) * char_time_);
}

void MemoryLink::deliver(Clock::time_point at, Bytes frame, uint64_t answers, const Bytes& request,
                         double late_by) {
  auto it = input_.begin();
  while (it != input_.end() && it->at <= at) ++it;
  input_.insert(it, Arrival{at, std::move(frame), answers, request, late_by});
}

void MemoryLink::dropInput(Clock::time_point up_to) {
  uint64_t dropped = 0;
  while (!input_.empty() && input_.front().at <= up_to) {
    fold(false, input_.front().frame);
    dropped += input_.front().frame.size();
    input_.pop_front();
    ++stale_dropped_;
  }
  if (dropped > 0) addStaleBytes(dropped);
}

void MemoryLink::awaitQuiet(Clock::time_point until) {
  const Clock::time_point give_up = clock_.now() + std::chrono::seconds(1);
  Clock::time_point now = clock_.now();
  while (now < until && now < give_up) {
    if (input_.empty() || input_.front().at >= until) {
      now = until;
      break;
    }
    now = std::max(now, input_.front().at + onWire(input_.front().frame.size()));
    dropInput(input_.front().at);
    until = std::max(until, now + seconds(config_.late_reply_guard));
  }
  if (now > clock_.now()) clock_.advanceTo(now);
}

Result MemoryLink::readReply(const EncodedRequest& request, LineEvent& event,
                             const char* no_reply) {
  const Clock::time_point deadline = clock_.now() + seconds(responseTimeout(request));
  if (input_.empty() || input_.front().at > deadline) {
    clock_.advanceTo(deadline);
    if (observer_) observer_(event);
    return Result::failure(ErrorKind::kTimeout, request.request().describe() + ": " + no_reply);
  }
  Arrival a = std::move(input_.front());
  input_.pop_front();
  if (a.at > clock_.now()) clock_.advanceTo(a.at);
  fold(false, a.frame);
  wire(a.frame.size());
  Result r = decodeReply(request, a.frame);
  event.stale = a.answers != attempt_id_;
  if (event.stale && r.ok()) {
    // The node took this attempt as answered: its own reply, still on its way, comes after a
    // request that did not fail, which the late-reply guard does not cover (F90: repetition).
    for (Arrival& mine : input_)
      if (mine.answers == attempt_id_) mine.late_by = 0;
  }
  if (event.stale) {
    ++stale_read_;
    event.refused = false;  // the node read another frame, not the device's refusal
    // F90: within the guard, only a retry of that request or a new read with its frame may
    // take it (a new write with its frame would be confirmed by an echo of the old one).
    const bool within_guard = r.ok() && a.late_by > 0 && a.late_by <= config_.late_reply_guard;
    const bool same_frame = a.request == request.adu();
    const bool new_read = !retrying() && isReadFunction(request.request().function);
    event.taken_within_guard = within_guard && !(same_frame && (retrying() || new_read));
    event.taken_by_same_read = within_guard && same_frame && new_read;
  }
  // Taken as the reply (a foreign or stale frame too, if it passes the reply checks) it counts
  // as an answer with its values.
  event.answered = r.ok() || (!event.stale && r.error == ErrorKind::kException);
  if (r.ok()) event.values = r.values;
  if (observer_) observer_(event);
  return r;
}

Result MemoryLink::attempt(const EncodedRequest& request) {
  if (port_lost_) {
    connected_ = false;
    return Result::failure(ErrorKind::kIo, "the adapter is gone (simulated port loss)");
  }
  ++attempt_id_;
  // The link's late-reply guard, on this line's clock; then whatever has arrived is flushed.
  if (const auto until = guardUntil(request)) {
    awaitQuiet(*until);
    lineSettled(request);
  }
  dropInput(clock_.now());
  const Bytes& adu = request.adu();
  fold(true, adu);
  wire(adu.size());
  LineEvent event;
  event.request = request.request();
  event.execute_id = execute_id_;
  event.at = clock_.now();
  const uint8_t slave = request.request().slave;
  SimDevice* target = nullptr;
  for (auto& d : devices_)
    if (d->answersTo(slave, &request.request()) && !faults_[d->address()].silent) {
      target = d.get();
      break;
    }
  if (!target) return readReply(request, event, "no reply");
  MemoryLinkFaults& f = faults_[target->address()];
  const Clock::time_point now = clock_.now();
  if (f.refused > 0) {
    // The device answers with an exception and does nothing.
    --f.refused;
    deliver(
        now,
        encodeException(slave, static_cast<uint8_t>(request.request().function), f.refused_code),
        attempt_id_);
    event.refused = true;
    return readReply(request, event, "no reply");
  }
  event.heard = true;
  std::optional<Bytes> reply = target->handle(request.request(), now);
  if (fail_after_frame_) {
    // The adapter fails with the request out: the device acted, no reply is read.
    fail_after_frame_ = false;
    setPortLost(true);
    event.port_failed = true;
    if (observer_) observer_(event);
    return Result::failure(ErrorKind::kIo,
                           request.request().describe() + ": the adapter failed after sending");
  }
  if (!reply) return readReply(request, event, "no reply");
  if (f.foreign > 0 && reply->size() >= 4) {
    // A well-formed frame that is not this request's reply (its CRC good): the node must
    // reject it; the device acted.
    --f.foreign;
    Bytes other;
    if (f.foreign_kind == ForeignFrame::kInserted) {
      other =
          encodeRequest(Request::readCoils(static_cast<uint8_t>(slave == 247 ? 246 : 247), 0, 8));
    } else {
      other.assign(reply->begin(), reply->end() - 2);  // without its CRC
      if (f.foreign_kind == ForeignFrame::kMasquerade)
        other[1] = static_cast<uint8_t>(other[1] == 0x03 ? 0x04 : 0x03);
      else
        other[0] = static_cast<uint8_t>(other[0] == 247 ? 246 : other[0] + 1);
      appendCrc(other);
    }
    deliver(now, std::move(other), 0);
    return readReply(request, event, "no reply");
  }
  if (f.lost > 0) {
    --f.lost;
    return readReply(request, event, "no reply (reply lost)");
  }
  if (f.late > 0) {
    // After the response timeout: on the line when a later request may be waiting.
    --f.late;
    deliver(now + seconds(responseTimeout(request) + f.late_by), *reply, attempt_id_, request.adu(),
            f.late_by);
    return readReply(request, event, "no reply (it came late)");
  }
  Bytes bytes = *reply;
  if (f.garbled > 0) {
    --f.garbled;
    bytes.back() ^= 0x5A;  // a bad CRC
  }
  if (f.repeated > 0) {
    --f.repeated;
    deliver(now + onWire(bytes.size()) + seconds(f.repeat_after), bytes, attempt_id_);
  }
  deliver(now, std::move(bytes), attempt_id_);
  return readReply(request, event, "no reply");
}

Result MemoryLink::sendBroadcast(const EncodedRequest& request) {
  dropInput(clock_.now());
  fold(true, request.adu());
  wire(request.adu().size());
  for (auto& d : devices_)
    if (!faults_[d->address()].silent) d->handleBroadcast(request.request(), clock_.now());
  return Result::success();
}

}  // namespace modbus_rtu_driver
