// Read planning for a generic device: which requests read a set of signals. Signals of one
// table that lie close together (at most max_gap unread registers or bits between them) are
// read in one request, within the protocol's limits (125 registers, 2000 bits). A device that
// refuses a merged span with exception 02 (illegal data address: an unmapped register in the
// gap) or 03 (illegal data value: a quantity longer than it serves, as Eastron meters answer)
// gets it split in two at its widest gap; the split is remembered, so later plans keep those
// signals apart. ROS-free.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "modbus_rtu_driver/core/config/signal.h"
#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

// One read request and the signals it carries (indices into the signal list, by address).
struct ReadSpan {
  Table table = Table::kHoldingRegister;
  uint16_t address = 0;
  uint16_t count = 0;  // registers or bits
  std::vector<size_t> signals;

  Request request(uint8_t slave) const;
  // "holding_register 0-9 (temperature, humidity)"
  std::string describe(const std::vector<SignalConfig>& all) const;
};

class ReadPlanner {
 public:
  ReadPlanner(std::vector<SignalConfig> signals, int max_gap);

  // The requests that read `which` (indices into signals()), by table then address.
  std::vector<ReadSpan> plan(const std::vector<size_t>& which) const;
  // After exception `code` (02 or 03) on `span`: splits it in two at its widest gap and
  // remembers the split. False for a span of one signal (nothing to split: that signal itself
  // is refused).
  bool split(const ReadSpan& span, ReadSpan* first, ReadSpan* second,
             uint8_t code = kIllegalDataAddress);
  // The splits made so far, in words, for diagnostics.
  const std::vector<std::string>& splits() const { return split_log_; }
  const std::vector<SignalConfig>& signals() const { return signals_; }

 private:
  ReadSpan spanOf(std::vector<size_t> signals) const;

  std::vector<SignalConfig> signals_;
  int max_gap_;
  // (table, address of a signal): never merged with the signal before it.
  std::set<std::pair<Table, uint16_t>> breaks_;
  std::vector<std::string> split_log_;
};

}  // namespace modbus_rtu_driver
