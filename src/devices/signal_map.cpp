#include "modbus_rtu_driver/devices/signal_map.h"

#include <algorithm>

#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

Request ReadSpan::request(uint8_t slave) const {
  switch (table) {
    case Table::kCoil:
      return Request::readCoils(slave, address, count);
    case Table::kDiscreteInput:
      return Request::readDiscreteInputs(slave, address, count);
    case Table::kHoldingRegister:
      return Request::readHoldingRegisters(slave, address, count);
    case Table::kInputRegister:
      break;
  }
  return Request::readInputRegisters(slave, address, count);
}

std::string ReadSpan::describe(const std::vector<SignalConfig>& all) const {
  return std::string(tableName(table)) + " " + std::to_string(address) + "-" +
         std::to_string(address + count - 1) + " (" +
         join(signals, ", ", [&all](size_t i) { return all[i].name; }) + ")";
}

ReadPlanner::ReadPlanner(std::vector<SignalConfig> signals, int max_gap)
    : signals_(std::move(signals)), max_gap_(max_gap) {}

ReadSpan ReadPlanner::spanOf(std::vector<size_t> which) const {
  ReadSpan span;
  const SignalConfig& first = signals_[which.front()];
  const SignalConfig& last = signals_[which.back()];
  span.table = first.table;
  span.address = first.address;
  span.count = static_cast<uint16_t>(last.address + last.words() - first.address);
  span.signals = std::move(which);
  return span;
}

std::vector<ReadSpan> ReadPlanner::plan(const std::vector<size_t>& which) const {
  std::vector<size_t> order = which;
  std::sort(order.begin(), order.end(), [this](size_t a, size_t b) {
    const SignalConfig &x = signals_[a], &y = signals_[b];
    return x.table != y.table ? x.table < y.table : x.address < y.address;
  });
  std::vector<ReadSpan> spans;
  std::vector<size_t> current;
  for (size_t i : order) {
    const SignalConfig& s = signals_[i];
    if (!current.empty()) {
      const SignalConfig& first = signals_[current.front()];
      const SignalConfig& prev = signals_[current.back()];
      const long gap = static_cast<long>(s.address) - (prev.address + prev.words());
      const long count = static_cast<long>(s.address) + s.words() - first.address;
      const long limit = isBitTable(s.table) ? kMaxReadBits : kMaxReadRegisters;
      const bool merge = s.table == first.table && gap <= max_gap_ && count <= limit &&
                         !breaks_.count({s.table, s.address});
      if (!merge) {
        spans.push_back(spanOf(current));
        current.clear();
      }
    }
    current.push_back(i);
  }
  if (!current.empty()) spans.push_back(spanOf(current));
  return spans;
}

bool ReadPlanner::split(const ReadSpan& span, ReadSpan* first, ReadSpan* second, uint8_t code) {
  if (span.signals.size() < 2) return false;
  size_t cut = 1;  // the first signal of the second part: after the widest gap
  long widest = -1;
  for (size_t k = 1; k < span.signals.size(); ++k) {
    const SignalConfig& prev = signals_[span.signals[k - 1]];
    const long gap =
        static_cast<long>(signals_[span.signals[k]].address) - (prev.address + prev.words());
    if (gap > widest) {
      widest = gap;
      cut = k;
    }
  }
  const SignalConfig& after = signals_[span.signals[cut]];
  breaks_.insert({after.table, after.address});
  *first = spanOf({span.signals.begin(), span.signals.begin() + static_cast<long>(cut)});
  *second = spanOf({span.signals.begin() + static_cast<long>(cut), span.signals.end()});
  split_log_.push_back(span.describe(signals_) + " refused (exception 0" + std::to_string(code) +
                       "): now read as " + first->describe(signals_) + " and " +
                       second->describe(signals_));
  return true;
}

}  // namespace modbus_rtu_driver
