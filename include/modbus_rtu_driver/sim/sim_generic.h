// Simulated generic device: built from the same signal description as the bus node's generic
// device (core/config/signal.h). Each table answers from its lowest to its highest signal register
// (a device's register block, gaps included, 0 until set); elsewhere, and in the configured
// `holes`, it answers exception 02, so a merged read across a hole is refused as on a device
// with an unmapped register. `max_read` (registers or bits per read) makes it answer longer
// reads with exception 03, as Eastron meters do. Coils and holding registers take writes;
// inputs are set through the control socket (`set`). Values survive a power cycle (the state
// file keeps them).
#pragma once

#include <map>
#include <vector>

#include "modbus_rtu_driver/core/config/device_types/generic.h"
#include "modbus_rtu_driver/core/config/signal.h"
#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

struct SimGenericConfig {
  SignalMapConfig map;
  struct Hole {
    Table table;
    uint16_t from, to;  // inclusive
  };
  std::vector<Hole> holes;
  uint16_t max_read = 0;  // registers or bits one read may ask; 0 = the protocol's limits
};

// The simulator's keys of a generic device beside the node's (holes, max_read).
extern const std::vector<std::string> kSimGenericKeys;

// Reads `signals`, `template`, `max_gap`, `holes` and `max_read` of a simulator device entry;
// throws config::ConfigError naming the key (core/config/config_yaml.h), as the node's parsers do.
// `base_dir`: where a relative template path starts.
void parseSimGeneric(const YAML::Node& entry, const std::string& where, const std::string& base_dir,
                     SimGenericConfig* out);

class SimGeneric : public SimDevice {
 public:
  SimGeneric(uint8_t address, SimLineSettings line, SimGenericConfig config);
  const char* type() const override { return kGenericType.name; }
  void powerCycle(SimClock::time_point) override {}
  uint16_t readLimit(bool bits) const override;
  void saveState(YAML::Node& node) const override;
  void loadState(const YAML::Node& node, SimClock::time_point now) override;
  uint8_t read(Table table, uint16_t address, SimClock::time_point now, uint16_t* value) override;
  uint8_t write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                SimClock::time_point now) override;
  uint8_t setDirect(Table table, uint16_t address, uint16_t value,
                    SimClock::time_point now) override;

 private:
  bool mapped(Table table, uint16_t address) const;

  SimGenericConfig config_;
  std::map<std::pair<Table, uint16_t>, uint16_t> values_;
  std::map<Table, std::pair<uint16_t, uint16_t>> blocks_;  // first and last address
};

}  // namespace modbus_rtu_driver
