#pragma once
// The one set of words for a value that is on or off, wherever one is taken (issue #33 item 5:
// safe_state, the configuration's true/false keys, the commissioning tool's power-down save,
// the simulator's silence and fail): on/off, true/false, yes/no, 1/0, in any case. rosparam's
// YAML turns yes/no/on/off (any case) into booleans, which reach the node as true/false, so a
// user's file means the same whichever way it is read; anything else is refused with the list.

#include <optional>
#include <string>
#include <string_view>

namespace modbus_rtu_driver {

inline constexpr std::string_view kSwitchWords = "on/off, true/false, yes/no, 1/0";
inline std::optional<bool> parseSwitch(std::string_view text) {
  std::string lower(text);
  for (char& c : lower) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  if (lower == "on" || lower == "true" || lower == "yes" || lower == "1") return true;
  if (lower == "off" || lower == "false" || lower == "no" || lower == "0") return false;
  return std::nullopt;
}

}  // namespace modbus_rtu_driver
