// Framing against every frame the manuals print (test/data/golden_frames.tsv).
#include <gtest/gtest.h>

#include "golden_frames.h"
#include "modbus_rtu_driver/core/modbus/frame.h"

using namespace modbus_rtu_driver;

namespace {
const std::vector<GoldenFrame>& golden() {
  static const auto rows = loadGoldenFrames(GOLDEN_FRAMES_PATH);
  return rows;
}
}  // namespace

TEST(Frame, GoldenFileIsLoaded) {
  ASSERT_GE(golden().size(), 50u);
  for (const auto& g : golden()) {
    EXPECT_FALSE(g.request.empty()) << g.meaning;
  }
}

TEST(Frame, Crc16KnownValue) {
  // "123456789" has CRC-16/MODBUS 0x4B37.
  const Bytes text{'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc16(text), 0x4B37);
}

TEST(Frame, EveryGoldenFrameHasValidCrc) {
  for (const auto& g : golden()) {
    EXPECT_TRUE(hasValidCrc(g.request)) << toHex(g.request) << " " << g.meaning;
    if (!g.response.empty()) {
      EXPECT_TRUE(hasValidCrc(g.response)) << toHex(g.response);
    }
  }
}

TEST(Frame, DecodeThenEncodeReproducesEveryGoldenRequest) {
  for (const auto& g : golden()) {
    std::string why;
    auto request = decodeRequest(g.request, &why);
    ASSERT_TRUE(request.has_value()) << toHex(g.request) << ": " << why;
    EXPECT_EQ(request->slave, g.slave) << g.meaning;
    if (g.slave == 0) request->single_device_at_zero = true;
    EXPECT_EQ(request->validate(), "") << g.meaning;
    EXPECT_EQ(toHex(encodeRequest(*request)), toHex(g.request)) << g.meaning;
  }
}

// Found by fuzz_frames: an FC15 whose last byte sets bits beyond the quantity. The spec asks
// for zeros there; like libmodbus, the decoder ignores them rather than refusing the frame.
TEST(Frame, UnusedBitsOfAnFc15AreIgnored) {
  Bytes padded = {0x01, 0x0F, 0x00, 0x02, 0x00, 0x01, 0x01, 0xFC};
  appendCrc(padded);
  std::string why;
  const auto request = decodeRequest(padded, &why);
  ASSERT_TRUE(request.has_value()) << why;
  EXPECT_EQ(request->values, std::vector<uint16_t>{0});
  EXPECT_EQ(request->validate(), "");
  EXPECT_EQ(toHex(encodeRequest(*request)),
            toHex(encodeRequest(Request::writeMultipleCoils(1, 2, {false}))));
}

TEST(Frame, BuildersProduceManualFrames) {
  EXPECT_EQ(toHex(encodeRequest(Request::readHoldingRegisters(0xFF, 0x00FD, 1))),
            "FF 03 00 FD 00 01 00 24");
  EXPECT_EQ(toHex(encodeRequest(Request::writeSingleCoil(0xFF, 0, true))),
            "FF 05 00 00 FF 00 99 E4");
  EXPECT_EQ(toHex(encodeRequest(Request::writeMultipleCoils(
                1, 0, {true, false, false, true, false, false, false, true}))),
            "01 0F 00 00 00 08 01 89 3F 33");
  EXPECT_EQ(toHex(encodeRequest(Request::writeMultipleRegisters(1, 0, {500, 200, 0xFFFF}))),
            "01 10 00 00 00 03 06 01 F4 00 C8 FF FF D6 CA");
  EXPECT_EQ(toHex(encodeRequest(Request::readInputRegisters(1, 0, 5))), "01 04 00 00 00 05 30 09");
}

TEST(Frame, DecodeGoldenReplies) {
  for (const auto& g : golden()) {
    if (g.response.empty()) continue;
    auto request = decodeRequest(g.request);
    ASSERT_TRUE(request.has_value());
    if (g.slave == 0) request->single_device_at_zero = true;
    if (g.slave == 0 && request->function == FunctionCode::kWriteMultipleRegisters)
      request->reply_echoes_request = true;
    EXPECT_EQ(replyLengthFromHeader(*request, g.response), g.response.size()) << g.meaning;
    const Result r = decodeReply(EncodedRequest::encode(*request).value(), g.response);
    EXPECT_TRUE(r.ok()) << g.meaning << ": " << r.message;
  }
}

TEST(Frame, DecodedValuesMatchTheManual) {
  auto rsp = [](const char* hex) { return *fromHex(hex); };
  Result r = decodeReply(EncodedRequest::encode(Request::readCoils(1, 0, 8)).value(),
                         rsp("01 01 01 7C 50 69"));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.values, (std::vector<uint16_t>{0, 0, 1, 1, 1, 1, 1, 0}));
  r = decodeReply(EncodedRequest::encode(Request::readInputRegisters(1, 0, 5)).value(),
                  rsp("01 04 0A 00 DD 02 71 08 98 02 D5 06 3B 86 51"));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.values, (std::vector<uint16_t>{221, 625, 2200, 725, 1595}));
  r = decodeReply(EncodedRequest::encode(Request::readHoldingRegisters(1, 0, 3)).value(),
                  rsp("01 03 06 09 C4 07 D0 06 40 D2 E0"));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.values, (std::vector<uint16_t>{2500, 2000, 1600}));
  Request addr0 = Request::readHoldingRegisters(0, 0, 1);
  addr0.single_device_at_zero = true;
  r = decodeReply(EncodedRequest::encode(addr0).value(), rsp("00 03 02 00 FF C5 C4"));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, (std::vector<uint16_t>{255}));
}

TEST(Frame, ManualsWrongCrcIsRejected) {
  // 002 prints "01 01 00 00 00 01 31 CA": the CRC belongs to the FC04 frame.
  std::string why;
  EXPECT_FALSE(decodeRequest(*fromHex("01 01 00 00 00 01 31 CA"), &why).has_value());
  EXPECT_EQ(why, "bad CRC");
}

TEST(Frame, ErrorsAreToldApart) {
  const Request req = Request::readHoldingRegisters(1, 0x00FD, 1);
  Bytes bad_crc = *fromHex("01 03 02 00 01 79 84");
  bad_crc.back() ^= 0xFF;
  EXPECT_EQ(decodeReply(EncodedRequest::encode(req).value(), bad_crc).error, ErrorKind::kCrc);
  Bytes other = {0x02, 0x03, 0x02, 0x00, 0x01};
  appendCrc(other);
  EXPECT_EQ(decodeReply(EncodedRequest::encode(req).value(), other).error,
            ErrorKind::kWrongAddress);
  const Result exc =
      decodeReply(EncodedRequest::encode(req).value(), encodeException(1, 0x03, 0x02));
  EXPECT_EQ(exc.error, ErrorKind::kException);
  EXPECT_EQ(exc.exception_code, 2);
  EXPECT_NE(exc.message.find("illegal data address"), std::string::npos) << exc.message;
  EXPECT_NE(exc.message.find("FC03"), std::string::npos) << exc.message;
  EXPECT_NE(exc.message.find("0x00FD"), std::string::npos) << exc.message;
  // A write whose echo differs is not a confirmation.
  EXPECT_EQ(decodeReply(EncodedRequest::encode(Request::writeSingleCoil(1, 0, true)).value(),
                        *fromHex("01 05 00 00 00 00 CD CA"))
                .error,
            ErrorKind::kMalformed);
}

TEST(Frame, RequestValidationNamesTheField) {
  EXPECT_NE(Request::readHoldingRegisters(1, 0, 126).validate().find("count"), std::string::npos);
  EXPECT_NE(Request::readCoils(0, 0, 8).validate().find("slave"), std::string::npos);
  EXPECT_NE(Request::readHoldingRegisters(1, 0xFFFF, 2).validate().find("address"),
            std::string::npos);
  EXPECT_EQ(Request::writeSingleCoil(0, 3, true).validate(), "");
}
