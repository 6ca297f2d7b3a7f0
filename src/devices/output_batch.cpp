#include "modbus_rtu_driver/devices/output_batch.h"

#include <map>

namespace modbus_rtu_driver {

std::shared_ptr<OutputBatch::Entry> OutputBatch::add(const Device& device,
                                                     std::vector<uint8_t> channels,
                                                     std::vector<bool> states) {
  auto entry = std::make_shared<Entry>();
  const std::string problem = device.checkOutputs(channels, states);
  entry->channels = std::move(channels);
  entry->states = std::move(states);
  if (!problem.empty()) {
    entry->result = Result::failure(ErrorKind::kInvalidArgument, problem);
    return entry;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.push_back(entry);
  return entry;
}

Result OutputBatch::write(Device& device, Transport& link, const std::vector<uint8_t>& channels,
                          const std::vector<bool>& states, const std::vector<bool>& timed_may_run) {
  const std::string problem = device.checkOutputs(channels, states);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  return device.writeOutputs(link, channels, states, nullptr, timed_may_run);
}

Result OutputBatch::complete(Device& device, Transport& link, const std::shared_ptr<Entry>& entry,
                             const WrittenCallback& on_written,
                             const NotConfirmedCallback& on_not_confirmed,
                             const std::vector<bool>& timed_may_run) {
  if (const std::optional<Result>& refused = entry->result) return *refused;
  std::vector<std::shared_ptr<Entry>> batch;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    batch.swap(pending_);
  }
  std::map<uint8_t, bool> wanted;  // in call order: the newest state per channel wins
  for (const auto& e : batch)
    for (size_t i = 0; i < e->channels.size() && i < e->states.size(); ++i)
      wanted[e->channels[i]] = e->states[i];
  std::vector<uint8_t> channels;
  std::vector<bool> states;
  for (const auto& [channel, state] : wanted) {
    channels.push_back(channel);
    states.push_back(state);
  }
  // Every entry was checked by add(), so their merge is a valid write: each channel in range and
  // once (the map), a state for each. It goes to the type's write without a second check.
  std::vector<uint8_t> changed;
  Result r = device.writeOutputs(link, channels, states, &changed, timed_may_run);
  if (r.ok() && on_written) on_written(channels, states);
  if (!r.ok() && on_not_confirmed) on_not_confirmed(channels, r, changed);
  if (batch.size() > 1 && r.ok())
    r.message = (r.message.empty() ? "" : r.message + "; ") + "merged with " +
                std::to_string(batch.size() - 1) + " other request(s) into one write";
  for (const auto& e : batch) {
    Result mine = r;
    for (size_t i = 0; r.ok() && i < e->channels.size() && i < e->states.size(); ++i) {
      if (wanted[e->channels[i]] == e->states[i]) continue;
      mine.message += "; output " + std::to_string(e->channels[i]) +
                      " superseded by a newer request in the same write";
      break;
    }
    e->result = std::move(mine);
  }
  // `entry` was in this batch: it was added before its job was queued, and jobs run in order.
  return entry->result.value_or(r);
}

}  // namespace modbus_rtu_driver
