// core/modbus/text.h: one table gives an enum its names and its parse; one join writes every list.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/modbus/text.h"

using namespace modbus_rtu_driver;

namespace {

// An enum of the test's own, so the test does not follow the driver's enums as they change.
enum class Colour { kRed, kGreen, kBlue, kUnnamed };

inline constexpr NameTable<Colour, 3> kColours{{
    {Colour::kRed, "red"},
    {Colour::kGreen, "green"},
    {Colour::kBlue, "blue"},
}};

}  // namespace

TEST(Text, NameAndParseComeFromOneTable) {
  static_assert(nameIn(kColours, Colour::kGreen) == "green");  // usable at compile time
  for (const auto& row : kColours) {
    EXPECT_EQ(nameIn(kColours, row.value), row.name);
    EXPECT_EQ(valueIn(kColours, row.name), row.value);  // each name parses back to its value
  }
  EXPECT_EQ(nameIn(kColours, Colour::kUnnamed), "?");  // a value the table lacks
}

TEST(Text, AParseOfAnUnknownNameFails) {
  EXPECT_EQ(valueIn(kColours, "purple"), std::nullopt);
  EXPECT_EQ(valueIn(kColours, "Red"), std::nullopt);  // names are exact: no case folding
  EXPECT_EQ(valueIn(kColours, ""), std::nullopt);
  EXPECT_EQ(valueIn(kColours, "red "), std::nullopt);
}

TEST(Text, NamesInListsTheTableInItsOrder) {
  EXPECT_EQ(namesIn(kColours), "red, green, blue");
  const NameTable<Colour, 1> one{{{Colour::kRed, "red"}}};
  EXPECT_EQ(namesIn(one), "red");
}

TEST(Text, JoinPutsTheSeparatorOnlyBetweenItems) {
  EXPECT_EQ(join(std::vector<std::string>{}), "");
  EXPECT_EQ(join(std::vector<std::string>{"a"}), "a");
  EXPECT_EQ(join(std::vector<std::string>{"a", "b", "c"}), "a, b, c");
  EXPECT_EQ(join(std::vector<std::string>{"a", "", "c"}), "a, , c");  // an empty item stays
  EXPECT_EQ(join(std::vector<int>{1, -2, 300}, " "), "1 -2 300");
  EXPECT_EQ(join(std::vector<uint16_t>{0, 65535}, " / "), "0 / 65535");
  EXPECT_EQ(join(std::set<std::string>{"b", "a"}), "a, b");  // any range, in its order
  const int bauds[] = {4800, 9600};
  EXPECT_EQ(join(bauds), "4800, 9600");
}

TEST(Text, JoinOfBytesNeedsAShowToPrintNumbers) {
  const std::vector<uint8_t> channels = {0, 7, 65};
  // `<<` writes a uint8_t as a character: 65 would be "A" and 0 a NUL byte.
  EXPECT_EQ(join(channels), std::string("\0, \a, A", 7));
  EXPECT_EQ(join(channels, ", ", [](uint8_t c) { return std::to_string(c); }), "0, 7, 65");
}

TEST(Text, JoinShowsEachItemThroughTheGivenFunction) {
  const std::map<std::string, int> keys = {{"address", 1}, {"type", 2}};
  EXPECT_EQ(join(keys, ", ", [](const auto& kv) { return kv.first; }), "address, type");
  EXPECT_EQ(
      join(keys, "; ", [](const auto& kv) { return kv.first + "=" + std::to_string(kv.second); }),
      "address=1; type=2");
  const std::vector<size_t> indices = {2, 0};
  const std::vector<std::string> names = {"x", "y", "z"};
  EXPECT_EQ(join(indices, ", ", [&names](size_t i) { return names[i]; }), "z, x");
}
