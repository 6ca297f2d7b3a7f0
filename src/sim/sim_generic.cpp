#include "modbus_rtu_driver/sim/sim_generic.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>

#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

// `type: generic` in the simulator's file builds this class from the entry's signals
// (sim/simulator.h).
[[maybe_unused]] const bool kSimGenericRegistered = simDeviceClasses().add(
    kGenericType,
    [](const SimulatorConfig::Entry& entry, SimLineSettings line) -> std::unique_ptr<SimDevice> {
      return std::make_unique<SimGeneric>(static_cast<uint8_t>(entry.address), line, entry.generic);
    });

namespace {

void parseHoles(const YAML::Node& n, const std::string& key, SimGenericConfig* out) {
  using namespace config;
  if (!n.IsSequence()) fail(key, show(n) + " is not a list of {table, from, to}");
  for (size_t i = 0; i < n.size(); ++i) {
    const std::string at = key + "[" + std::to_string(i) + "]/";
    checkKeys(n[i], at, {"table", "from", "to"});
    SimGenericConfig::Hole h{};
    h.table = getTable(n[i]["table"], at + "table");
    const int from = getInt(n[i]["from"], at + "from");
    const int to = n[i]["to"] ? getInt(n[i]["to"], at + "to") : from;
    if (from < 0 || to < from || to > 0xFFFF)
      fail(at + "to",
           std::to_string(from) + "-" + std::to_string(to) + " is not a range in 0-65535");
    h.from = static_cast<uint16_t>(from);
    h.to = static_cast<uint16_t>(to);
    out->holes.push_back(h);
  }
}

}  // namespace

const std::vector<std::string> kSimGenericKeys = {"holes", "max_read"};

void parseSimGeneric(const YAML::Node& entry, const std::string& where, const std::string& base_dir,
                     SimGenericConfig* out) {
  out->map = parseSignalMap(entry, where, base_dir);
  if (entry["holes"]) parseHoles(entry["holes"], where + "holes", out);
  if (entry["max_read"]) {
    const int n = config::getInt(entry["max_read"], where + "max_read");
    if (n < 1 || n > kMaxReadBits)
      config::fail(where + "max_read", std::to_string(n) + " is outside 1-2000");
    out->max_read = static_cast<uint16_t>(n);
  }
}

SimGeneric::SimGeneric(uint8_t address, SimLineSettings line, SimGenericConfig config)
    : SimDevice(address, line), config_(std::move(config)) {
  for (const SignalConfig& s : config_.map.signals) {
    const uint16_t last = static_cast<uint16_t>(s.address + s.words() - 1);
    auto it = blocks_.find(s.table);
    if (it == blocks_.end())
      blocks_[s.table] = {s.address, last};
    else
      it->second = {std::min(it->second.first, s.address), std::max(it->second.second, last)};
  }
}

uint16_t SimGeneric::readLimit(bool bits) const {
  const uint16_t protocol = SimDevice::readLimit(bits);
  return config_.max_read == 0 ? protocol : std::min(protocol, config_.max_read);
}

bool SimGeneric::mapped(Table table, uint16_t address) const {
  auto it = blocks_.find(table);
  if (it == blocks_.end() || address < it->second.first || address > it->second.second)
    return false;
  for (const auto& h : config_.holes)
    if (h.table == table && address >= h.from && address <= h.to) return false;
  return true;
}

uint8_t SimGeneric::read(Table table, uint16_t address, SimClock::time_point, uint16_t* value) {
  const Table t = table;
  if (!mapped(t, address)) return kIllegalDataAddress;
  auto it = values_.find({t, address});
  *value = it == values_.end() ? 0 : it->second;
  return 0;
}

// A write touching an unmapped address changes nothing (checked as a whole).
uint8_t SimGeneric::write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                          SimClock::time_point) {
  const Table t = table;
  for (size_t i = 0; i < values.size(); ++i)
    if (address + i > 0xFFFF || !mapped(t, static_cast<uint16_t>(address + i)))
      return kIllegalDataAddress;
  for (size_t i = 0; i < values.size(); ++i)
    values_[{t, static_cast<uint16_t>(address + i)}] = values[i];
  return 0;
}

uint8_t SimGeneric::setDirect(Table table, uint16_t address, uint16_t value,
                              SimClock::time_point now) {
  if (isBitTable(table) && value > 1) return kIllegalDataValue;
  return write(table, address, {value}, now);
}

void SimGeneric::saveState(YAML::Node& n) const {
  n["address"] = static_cast<int>(address_);
  for (const auto& kv : values_) {
    YAML::Node v;
    v.push_back(tableName(kv.first.first));
    v.push_back(kv.first.second);
    v.push_back(kv.second);
    n["values"].push_back(v);
  }
}

void SimGeneric::loadState(const YAML::Node& n, SimClock::time_point) {
  const int address = n["address"].as<int>(address_);
  if (address >= 1 && address <= 247) address_ = static_cast<uint8_t>(address);
  if (!n["values"] || !n["values"].IsSequence()) return;
  for (const auto& v : n["values"]) {
    if (!v.IsSequence() || v.size() != 3) continue;
    const std::string table = v[0].as<std::string>("");
    const auto t = valueIn(kTableNames, table);
    if (t && mapped(*t, v[1].as<uint16_t>(0)))
      values_[{*t, v[1].as<uint16_t>(0)}] = v[2].as<uint16_t>(0);
  }
}

}  // namespace modbus_rtu_driver
