// Issue #26 item 4: one request, checked and encoded once, where the link takes it. Every attempt
// (retries included) sends that frame, the response timeout is sized from it and a write's reply
// is compared with it. Proved by the API's shape, not by counting calls: past Link::execute
// nothing takes a bare Request it could encode again (the static_asserts, and the link below,
// which would not compile if attempt() took a Request), and every attempt is handed the same
// frame object.
#include <gtest/gtest.h>

#include <deque>
#include <type_traits>
#include <utility>
#include <vector>

#include "modbus_rtu_driver/core/link/link.h"

namespace modbus_rtu_driver {
namespace {

// Whether decodeReply can be called with a T and the reply bytes.
template <class T, class = void>
struct DecodesFrom : std::false_type {};
template <class T>
struct DecodesFrom<
    T, std::void_t<decltype(decodeReply(std::declval<const T&>(), std::declval<const Bytes&>()))>>
    : std::true_type {};

static_assert(DecodesFrom<EncodedRequest>::value, "the echo check reads the frame that was sent");
static_assert(!DecodesFrom<Request>::value,
              "given a bare Request, the echo check would have to encode it again");
static_assert(!std::is_constructible_v<EncodedRequest, Request> &&
                  !std::is_convertible_v<Request, EncodedRequest>,
              "only EncodedRequest::encode makes one, and it checks the request as it encodes");

// A link whose medium is a script: it records what each attempt was handed and answers with
// the next reply (none: a timeout).
class RecordingLink : public Link {
 public:
  explicit RecordingLink(LinkConfig config) : Link(std::move(config)) {}

  std::deque<Bytes> replies;
  std::vector<const EncodedRequest*> handed;  // the object each attempt got
  std::vector<Bytes> sent;                    // its bytes
  std::vector<double> timeouts;
  int broadcasts = 0;

 protected:
  Result attempt(const EncodedRequest& request) override {
    handed.push_back(&request);
    sent.push_back(request.adu());
    timeouts.push_back(responseTimeout(request));
    Bytes reply;
    if (!replies.empty()) {
      reply = replies.front();
      replies.pop_front();
    }
    if (reply.empty())
      return Result::failure(ErrorKind::kTimeout, request.request().describe() + ": no reply");
    return decodeReply(request, reply);
  }
  Result sendBroadcast(const EncodedRequest& request) override {
    ++broadcasts;
    sent.push_back(request.adu());
    return Result::success(request.request().values);
  }
  double minGap() const override { return 0; }
};

LinkConfig config(int retries) {
  LinkConfig c;
  c.port = "/dev/null";
  c.retries = retries;
  return c;
}

Bytes hex(const char* text) {
  return *fromHex(text);
}

// A SetBool of output 0 on slave 1 as the devices build it (FC05), its reply lost twice.
TEST(EncodeOnce, EveryAttemptSendsTheOneFrame) {
  RecordingLink link(config(2));
  link.replies = {{}, {}, hex("01 05 00 00 FF 00 8C 3A")};
  const Result r = link.execute(Request::writeSingleCoil(1, 0, true));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, (std::vector<uint16_t>{1}));
  ASSERT_EQ(link.handed.size(), 3u);
  for (size_t i = 0; i < link.handed.size(); ++i) {
    EXPECT_EQ(link.handed[i], link.handed[0]) << "attempt " << i << " got another frame";
    EXPECT_EQ(toHex(link.sent[i]), "01 05 00 00 FF 00 8C 3A") << "attempt " << i;
  }
  EXPECT_EQ(link.stats().attempts, 3u);
  EXPECT_EQ(link.stats().retries, 2u);
}

// The timeout is sized from the frame's length (8 bytes on the wire at the configured baud).
TEST(EncodeOnce, TheTimeoutComesFromTheFrame) {
  RecordingLink link(config(0));
  link.setReplyDelay(1, 0.25);
  link.replies = {hex("01 05 00 00 FF 00 8C 3A")};
  ASSERT_TRUE(link.execute(Request::writeSingleCoil(1, 0, true)).ok());
  ASSERT_EQ(link.timeouts.size(), 1u);
  EXPECT_DOUBLE_EQ(link.timeouts[0], effectiveResponseTimeout(link.config(), 8) + 0.25);
}

// The echo check compares with the frame sent: a reply confirming another state is refused.
TEST(EncodeOnce, AWriteIsConfirmedAgainstTheFrameSent) {
  RecordingLink link(config(0));
  link.replies = {hex("01 05 00 00 00 00 CD CA")};
  const Result r = link.execute(Request::writeSingleCoil(1, 0, true));
  EXPECT_EQ(r.error, ErrorKind::kMalformed);
  EXPECT_NE(r.message.find("does not confirm the write"), std::string::npos) << r.message;
}

// The one check: an invalid request is refused at the link's entry, with the text it always
// had, and no attempt is made.
TEST(EncodeOnce, AnInvalidRequestIsRefusedBeforeAnyAttempt) {
  RecordingLink link(config(2));
  Request bad = Request::writeSingleCoil(1, 0, true);
  bad.values = {2};
  const Result r = link.execute(bad);
  EXPECT_EQ(r.error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(r.message,
            "FC05 write single coil, slave 1, address 0x0000, count 1: values: coil states must "
            "be 0 or 1");
  EXPECT_TRUE(link.handed.empty());
  EXPECT_EQ(link.stats().requests, 0u);
}

// A broadcast goes out once, as encoded.
TEST(EncodeOnce, ABroadcastIsSentAsEncoded) {
  RecordingLink link(config(2));
  ASSERT_TRUE(link.execute(Request::writeSingleCoil(0, 3, true)).ok());
  EXPECT_EQ(link.broadcasts, 1);
  ASSERT_EQ(link.sent.size(), 1u);
  EXPECT_EQ(link.sent[0], encodeRequest(Request::writeSingleCoil(0, 3, true)));
}

// EncodedRequest::encode refuses what Request::validate refuses, and otherwise gives the bytes
// (and the reply length) of the frame.
TEST(EncodeOnce, EncodeChecksAndGivesTheWireBytes) {
  Result refused;
  EXPECT_FALSE(EncodedRequest::encode(Request::readHoldingRegisters(1, 0, 126), &refused));
  EXPECT_EQ(refused.error, ErrorKind::kInvalidArgument);
  EXPECT_NE(refused.message.find("count: 126 is outside 1-125"), std::string::npos)
      << refused.message;
  const auto read =
      EncodedRequest::encode(Request::readHoldingRegisters(255, 0x00FD, 1));  // 000/ld58a08
  ASSERT_TRUE(read);
  EXPECT_EQ(toHex(read->adu()), "FF 03 00 FD 00 01 00 24");
  EXPECT_EQ(read->replyLength(), 7u);
  Request set_address = Request::writeMultipleRegisters(0, 0, {200});
  set_address.single_device_at_zero = true;
  set_address.reply_echoes_request = true;
  const auto echoed = EncodedRequest::encode(set_address);
  ASSERT_TRUE(echoed);
  EXPECT_EQ(echoed->replyLength(), echoed->adu().size());  // the LC board echoes it whole
}

}  // namespace
}  // namespace modbus_rtu_driver
