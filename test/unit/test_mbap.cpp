// MBAP framing: the conversion to and from RTU ADUs, byte exact, and the header checks.
#include <gtest/gtest.h>

#include "modbus_rtu_driver/core/modbus/mbap.h"

namespace modbus_rtu_driver {
namespace {

Bytes hex(const char* text) {
  return *fromHex(text);
}

TEST(Mbap, RequestCarriesTheRtuPduWithoutCrc) {
  const Bytes rtu = encodeRequest(Request::readHoldingRegisters(1, 0x0000, 10));
  EXPECT_EQ(toHex(rtu), "01 03 00 00 00 0A C5 CD");
  EXPECT_EQ(toHex(rtuToMbap(0x1234, rtu)), "12 34 00 00 00 06 01 03 00 00 00 0A");
}

TEST(Mbap, ReplyBackToRtuGetsAFreshCrcAndDecodes) {
  const Request request = Request::readHoldingRegisters(17, 0x006B, 3);
  const Bytes mbap = hex("00 07 00 00 00 09 11 03 06 02 2B 00 00 00 64");
  EXPECT_EQ(mbapTransaction(mbap), 7);
  const Bytes rtu = mbapToRtu(mbap);
  EXPECT_TRUE(hasValidCrc(rtu));
  const Result r = decodeReply(EncodedRequest::encode(request).value(), rtu);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, (std::vector<uint16_t>{0x022B, 0x0000, 0x0064}));
}

TEST(Mbap, RoundTripOfAnExceptionReply) {
  const Bytes rtu = encodeException(5, 0x03, kIllegalDataAddress);
  const Bytes mbap = rtuToMbap(0xFFFF, rtu);
  EXPECT_EQ(toHex(mbap), "FF FF 00 00 00 03 05 83 02");
  EXPECT_EQ(mbapToRtu(mbap), rtu);
}

TEST(Mbap, LengthFromHeader) {
  std::string error;
  EXPECT_EQ(mbapLengthFromHeader(hex("00 01 00 00 00")), 0);
  EXPECT_EQ(mbapLengthFromHeader(hex("00 01 00 00 00 06")), 12);
  EXPECT_EQ(mbapLengthFromHeader(hex("00 01 00 01 00 06"), &error), -1);
  EXPECT_EQ(error, "MBAP protocol id 1 is not 0 (Modbus)");
  EXPECT_EQ(mbapLengthFromHeader(hex("00 01 00 00 00 01"), &error), -1);
  EXPECT_EQ(error, "MBAP length 1 is outside 2-254");
  EXPECT_EQ(mbapLengthFromHeader(hex("00 01 00 00 00 FF"), &error), -1);
  EXPECT_EQ(mbapLengthFromHeader(hex("00 01 00 00 00 FE")), 260);
}

TEST(Mbap, ShortInputsAreEmptyNotOutOfBounds) {
  EXPECT_TRUE(mbapToRtu(hex("00 01 00")).empty());
  EXPECT_EQ(mbapTransaction(Bytes{}), 0);
  EXPECT_EQ(toHex(rtuToMbap(1, Bytes{})), "00 01 00 00 00 00");
}

}  // namespace
}  // namespace modbus_rtu_driver
