// Reading configuration from YAML, key by key: the pieces every configuration parser shares
// (the bus node's, the slave role's). A rule that fails throws ConfigError naming the key, the
// value and what is allowed; parseWith turns the first one into the parser's error message.
#pragma once

#include <yaml-cpp/yaml.h>

#include <set>
#include <string>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/modbus/switch_words.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {
namespace config {

struct ConfigError {
  std::string message;
};

[[noreturn]] void fail(const std::string& key, const std::string& what);
// How a value looks in an error message: 'text', a list, a map, nothing.
std::string show(const YAML::Node& n);

template <typename T>
T get(const YAML::Node& n, const std::string& key, const char* expected) {
  try {
    return n.as<T>();
  } catch (const YAML::Exception&) {
    fail(key, show(n) + " is not " + expected);
  }
}

// One of an enum's names (its NameTable); otherwise fails naming the key and the names.
template <typename E, std::size_t N>
E getNamed(const YAML::Node& n, const std::string& key, const NameTable<E, N>& names) {
  const std::string list = namesIn(names);
  const std::string text = get<std::string>(n, key, list.c_str());
  if (auto value = valueIn(names, text)) return *value;
  fail(key, "'" + text + "' is not one of " + list);
}
// A Modbus table by its one name; a spelling of earlier versions is refused with the name.
Table getTable(const YAML::Node& n, const std::string& key);

// A value that is on or off: one of kSwitchWords (on/off, true/false, yes/no, 1/0, any case);
// otherwise fails naming the key and the words.
bool getSwitch(const YAML::Node& n, const std::string& key);
double getNumber(const YAML::Node& n, const std::string& key);
int getInt(const YAML::Node& n, const std::string& key);  // decimal, or hex as 0x...
// Fails on the first key of `map` that is not in `known`, listing the known ones.
void checkKeys(const YAML::Node& map, const std::string& where, const std::set<std::string>& known);
std::set<std::string> with(std::set<std::string> keys, const std::set<std::string>& more);

// The serial line's keys, shared by both roles.
extern const std::set<std::string> kLinkKeys;
// The link's keys, then validateLinkConfig (the line settings: the port is the role's to check).
void parseLink(const YAML::Node& root, LinkConfig* out);
// The link's keys alone (their types checked, not their values).
void readLink(const YAML::Node& root, LinkConfig* out);
double parseDiagnosticPeriod(const YAML::Node& root);

// Runs a parser; its first error becomes the message.
template <typename Config>
inline bool parseWith(void (*parser)(const YAML::Node&, Config*), const YAML::Node& root,
                      Config* out, std::string* error) {
  *out = Config{};
  try {
    parser(root, out);
    return true;
  } catch (const ConfigError& e) {
    if (error) *error = e.message;
  } catch (const YAML::Exception& e) {
    if (error) *error = std::string("configuration: ") + e.what();
  }
  return false;
}

}  // namespace config

// True when `name` is a valid ROS graph name segment: a letter, then letters, digits, '_'.
bool isValidRosName(const std::string& name);

}  // namespace modbus_rtu_driver
