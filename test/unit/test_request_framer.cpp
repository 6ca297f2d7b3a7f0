// Cutting a master's byte stream into request frames.
#include <gtest/gtest.h>

#include "modbus_rtu_driver/core/modbus/request_framer.h"

using namespace modbus_rtu_driver;

namespace {
Bytes frame(const Request& r) {
  return encodeRequest(r);
}
Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}
}  // namespace

TEST(RequestFramer, BackToBackFramesWithoutSilence) {
  RequestFramer f;
  const Bytes a = frame(Request::readHoldingRegisters(2, 0, 1));
  const Bytes b = *fromHex("01 10 00 05 00 02 04 08 07 0A 09 46 97");
  const Bytes both = cat({a, b});
  f.push(both.data(), 5);  // arrives in pieces
  EXPECT_TRUE(f.take(false).empty());
  f.push(both.data() + 5, both.size() - 5);
  const auto frames = f.take(false);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0], a);
  EXPECT_EQ(frames[1], b);
  EXPECT_FALSE(f.pending());
  EXPECT_EQ(f.dropped(), 0u);
}

TEST(RequestFramer, NoiseAndBadCrcAreDroppedAtSilence) {
  RequestFramer f;
  Bytes bad = frame(Request::readCoils(1, 0, 8));
  bad.back() ^= 1;
  const Bytes good = frame(Request::readCoils(1, 0, 8));
  const Bytes stream = cat({Bytes{0x00, 0xFF, 0x13}, good, bad, good});
  f.push(stream.data(), stream.size());
  EXPECT_TRUE(f.take(false).empty()) << "noise in front: wait for the silence";
  const auto frames = f.take(true);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0], good);
  EXPECT_EQ(frames[1], good);
  EXPECT_EQ(f.dropped(), 2u);
  EXPECT_FALSE(f.pending());
}

TEST(RequestFramer, UnknownFunctionIsOneFrameAtSilence) {
  RequestFramer f;
  Bytes unknown{0x01, 0x2B, 0x0E, 0x01};
  appendCrc(unknown);
  f.push(unknown.data(), unknown.size());
  EXPECT_TRUE(f.take(false).empty());
  const auto frames = f.take(true);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0], unknown);
  const Bytes junk{0x55, 0x66, 0x77};
  f.push(junk.data(), junk.size());
  EXPECT_TRUE(f.take(true).empty());
  EXPECT_EQ(f.dropped(), 1u);
}
