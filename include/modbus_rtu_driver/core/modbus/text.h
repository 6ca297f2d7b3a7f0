#pragma once
// Text written once: an enum's names in one table that drives both its name and its parse, and
// one join for every "a, b, c" list a message shows.

#include <array>
#include <cstddef>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace modbus_rtu_driver {

template <typename E>
struct Named {
  E value;
  std::string_view name;
};

// The names of an enum, one row per value: `inline constexpr NameTable<E, N> kEs{{...}};`.
template <typename E, std::size_t N>
using NameTable = std::array<Named<E>, N>;

template <typename E, std::size_t N>
constexpr std::string_view nameIn(const NameTable<E, N>& table, E value) {
  for (const auto& row : table)
    if (row.value == value) return row.name;
  return "?";
}

template <typename E, std::size_t N>
std::optional<E> valueIn(const NameTable<E, N>& table, std::string_view name) {
  for (const auto& row : table)
    if (row.name == name) return row.value;
  return std::nullopt;
}

// "a, b, c" (or with another separator): each item as `show` writes it, or as `<<` writes it.
template <typename Range, typename Show>
std::string join(const Range& items, std::string_view separator, const Show& show) {
  std::string out;
  bool first = true;
  for (const auto& item : items) {
    if (!first) out += separator;
    first = false;
    out += show(item);
  }
  return out;
}

template <typename Range>
std::string join(const Range& items, std::string_view separator = ", ") {
  return join(items, separator, [](const auto& item) {
    std::ostringstream text;
    text << item;
    return text.str();
  });
}

// "none, even, odd": the names a table accepts, for an error message.
template <typename E, std::size_t N>
std::string namesIn(const NameTable<E, N>& table) {
  return join(table, ", ", [](const Named<E>& row) { return std::string(row.name); });
}

}  // namespace modbus_rtu_driver
