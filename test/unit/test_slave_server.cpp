// The slave role's core over a real pty: the DM500's frames, exceptions, broadcasts, and valid
// requests right after frames for other ids or with bad CRCs.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <mutex>
#include <thread>

#include "modbus_rtu_driver/core/server/slave_server.h"
#include "pty_pair.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

namespace {

class SlaveServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SlaveConfig c;
    c.link.port = pty_.path();
    c.slave_id = 1;
    c.coils = c.discrete_inputs = c.holding_registers = c.input_registers = 64;
    server_ = std::make_unique<SlaveServer>(c, [this](const SlaveWrite& w) {
      std::lock_guard<std::mutex> lock(m_);
      writes_.push_back(w);
    });
    server_->start();
    ASSERT_TRUE(waitFor([this] { return server_->stats().port_open; }));
  }
  // Sends `hex`, returns what came back within `ms` (as soon as `expect` bytes are there).
  Bytes ask(const Bytes& frame, size_t expect, int ms = 3000) {
    pty_.read(256, 1);  // drop anything stale
    pty_.write(frame);
    return pty_.read(expect, ms);
  }
  Bytes ask(const std::string& hex, size_t expect, int ms = 3000) {
    return ask(*fromHex(hex), expect, ms);
  }
  std::vector<SlaveWrite> writes() {
    std::lock_guard<std::mutex> lock(m_);
    return writes_;
  }

  PtyPair pty_;
  std::unique_ptr<SlaveServer> server_;
  std::mutex m_;
  std::vector<SlaveWrite> writes_;
};

}  // namespace

TEST_F(SlaveServerTest, TheManualsTwoFrames) {
  EXPECT_EQ(toHex(ask("01 0F 00 06 00 0C 02 03 04 E4 E5", 8)),
            toHex(encodeReply(*decodeRequest(*fromHex("01 0F 00 06 00 0C 02 03 04 E4 E5")), {})));
  EXPECT_EQ(
      toHex(ask("01 10 00 05 00 02 04 08 07 0A 09 46 97", 8)),
      toHex(encodeReply(*decodeRequest(*fromHex("01 10 00 05 00 02 04 08 07 0A 09 46 97")), {})));
  // The server hands a write on after it has sent the reply.
  ASSERT_TRUE(waitFor([this] { return writes().size() >= 2; })) << writes().size();
  const auto w = writes();
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].table, Table::kCoil);
  EXPECT_EQ(w[0].address, 6);
  EXPECT_EQ(w[0].values, (std::vector<uint16_t>{1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0}));
  EXPECT_EQ(w[1].table, Table::kHoldingRegister);
  EXPECT_EQ(w[1].address, 5);
  EXPECT_EQ(w[1].values, (std::vector<uint16_t>{0x0807, 0x0A09}));
  EXPECT_EQ(registersToMacroBytes(w[1].values), (std::vector<uint8_t>{7, 8, 9, 10}));
  // And the master reads back what it wrote.
  const Request read = Request::readHoldingRegisters(1, 5, 2);
  EXPECT_EQ(toHex(ask(encodeRequest(read), 9)), toHex(encodeReply(read, {0x0807, 0x0A09})));
}

TEST_F(SlaveServerTest, SettersAreWhatTheMasterReads) {
  EXPECT_EQ(server_->set(Table::kInputRegister, 10, {500, 600}), "");
  EXPECT_EQ(server_->set(Table::kDiscreteInput, 0, {1, 0, 1}), "");
  // set() queues the change; the server thread applies it at the top of its next loop, so a
  // request it is already waiting for may still be answered from the old table: ask again
  // until the new values show (bounded), rather than sleeping and hoping the loop came round.
  const Request ir = Request::readInputRegisters(1, 10, 2);
  const std::string ir_reply = toHex(encodeReply(ir, {500, 600}));
  std::string got;
  EXPECT_TRUE(waitFor([&] { return (got = toHex(ask(encodeRequest(ir), 9))) == ir_reply; }));
  EXPECT_EQ(got, ir_reply);
  // The discrete inputs were queued before that request went out: the server's loop applies
  // them before it reads the next one.
  const Request di = Request::readDiscreteInputs(1, 0, 3);
  EXPECT_EQ(toHex(ask(encodeRequest(di), 6)), toHex(encodeReply(di, {1, 0, 1})));
  const std::string e = server_->set(Table::kHoldingRegister, 63, {1, 2});
  EXPECT_NE(e.find("holding_register 0-63"), std::string::npos) << e;
  EXPECT_NE(server_->set(Table::kCoil, 0, {2}), "");
}

TEST_F(SlaveServerTest, OutOfRangeGetsException02AndNoWrite) {
  const Request r = Request::readHoldingRegisters(1, 64, 1);
  EXPECT_EQ(toHex(ask(encodeRequest(r), 5)), toHex(encodeException(1, 0x03, kIllegalDataAddress)));
  const Request w = Request::writeMultipleRegisters(1, 63, {1, 2});
  EXPECT_EQ(toHex(ask(encodeRequest(w), 5)), toHex(encodeException(1, 0x10, kIllegalDataAddress)));
  // The server counts an exception after it has written it.
  EXPECT_TRUE(waitFor([this] { return server_->stats().exceptions_sent >= 2; }));
  EXPECT_EQ(server_->stats().exceptions_sent, 2u);
  EXPECT_TRUE(writes().empty());
}

TEST_F(SlaveServerTest, BroadcastIsAppliedNotAnswered) {
  EXPECT_TRUE(ask(encodeRequest(Request::writeSingleRegister(0, 20, 4242)), 1, 300).empty());
  const Request r = Request::readHoldingRegisters(1, 20, 1);
  EXPECT_EQ(toHex(ask(encodeRequest(r), 7)), toHex(encodeReply(r, {4242})));
  ASSERT_EQ(writes().size(), 1u);
  EXPECT_TRUE(writes()[0].broadcast);
}

// A frame with a function code of 0x80 or above is an exception reply, not a request: never
// answered (libmodbus would have sent function + 0x80, overflowed, found by the fuzzer).
TEST_F(SlaveServerTest, ExceptionRepliesAreNotAnswered) {
  const Bytes heard = encodeException(1, 0xDE, kIllegalFunction);  // "01 DE 01 ..."
  EXPECT_TRUE(ask(heard, 1, 300).empty());
  const Request r = Request::readHoldingRegisters(1, 0, 1);
  EXPECT_EQ(toHex(ask(encodeRequest(r), 7)), toHex(encodeReply(r, {0})));
  EXPECT_EQ(server_->stats().not_requests, 1u);
  EXPECT_EQ(server_->stats().exceptions_sent, 0u);
}

TEST_F(SlaveServerTest, ValidRequestsAfterOtherIdsAndBadCrcsAreAnswered) {
  const Request mine = Request::readHoldingRegisters(1, 0, 2);
  const Bytes reply = encodeReply(mine, {0, 0});
  for (int round = 0; round < 5; ++round) {
    Bytes burst = encodeRequest(Request::readHoldingRegisters(2, 0, 1));  // another id
    const Bytes valid = encodeRequest(mine);
    burst.insert(burst.end(), valid.begin(), valid.end());  // back to back, no gap
    EXPECT_EQ(toHex(ask(burst, reply.size())), toHex(reply)) << "after another id, round " << round;
    Bytes bad = encodeRequest(Request::readCoils(1, 0, 8));
    bad.back() ^= 0x5A;
    bad.insert(bad.end(), valid.begin(), valid.end());
    EXPECT_EQ(toHex(ask(bad, reply.size())), toHex(reply)) << "after a bad CRC, round " << round;
    Bytes noise{0x00, 0xFF, 0x13, 0x37};
    noise.insert(noise.end(), valid.begin(), valid.end());
    EXPECT_EQ(toHex(ask(noise, reply.size())), toHex(reply)) << "after noise, round " << round;
  }
  // The server counts a request after it has written the reply: the last one may still be due.
  EXPECT_TRUE(waitFor([this] { return server_->stats().requests_served >= 15; }));
  const SlaveStats s = server_->stats();
  EXPECT_GE(s.other_slave, 5u);
  EXPECT_GE(s.crc_errors, 5u);
  EXPECT_GE(s.requests_served, 15u);
  EXPECT_GE(s.since_last_heard, 0.0);
}

TEST_F(SlaveServerTest, ARequestRightAfterABadQuantityIsStillAnswered) {
  // libmodbus 3.1.6's modbus_reply sleeps a response timeout and flushes the input before it
  // answers a bad quantity: the valid request that follows would be lost.
  const Request mine = Request::readHoldingRegisters(1, 5, 1);
  const Bytes reply = encodeReply(mine, {0});
  for (const char* bad : {"01 03 00 35 01 15", "01 01 00 00 00 00", "01 10 00 00 00 02 02 00 01"}) {
    Bytes frame = *fromHex(bad);
    appendCrc(frame);
    const uint8_t function = frame[1];
    pty_.read(256, 1);
    pty_.write(frame);
    std::this_thread::sleep_for(std::chrono::milliseconds(15));
    pty_.write(encodeRequest(mine));
    EXPECT_EQ(toHex(pty_.read(5 + reply.size(), 3000)),
              toHex(encodeException(1, function, kIllegalDataValue)) + " " + toHex(reply))
        << bad;
  }
}

TEST(SlaveConfig, ParsesTheIssueExampleAndNamesBadKeys) {
  const char* yaml = R"(
port: /dev/ttyS1
baud: 9600
role: slave
slave_id: 1
coil: 64
discrete_input: 64
holding_register: 64
input_register: 64
names:
  coil: {6: spindle_ready}
  holding_register: {5: job_number}
)";
  SlaveConfig c;
  std::string error;
  ASSERT_TRUE(parseSlaveConfig(YAML::Load(yaml), &c, &error)) << error;
  EXPECT_EQ(c.link.port, "/dev/ttyS1");
  EXPECT_EQ(c.slave_id, 1);
  EXPECT_EQ(c.coil_names.at(6), "spindle_ready");
  EXPECT_EQ(c.holding_names.at(5), "job_number");
  ASSERT_TRUE(parseSlaveConfig(YAML::Load("role: slave\nslave_id: 3\nnames: {coil: {ready: 2}}"),
                               &c, &error))
      << error;
  EXPECT_EQ(c.coil_names.at(2), "ready");
  auto errorOf = [](const std::string& y) {
    SlaveConfig c;
    std::string e;
    return parseSlaveConfig(YAML::Load(y), &c, &e) ? std::string() : e;
  };
  EXPECT_NE(errorOf("role: slave\nslave_id: 248").find("slave_id: 248 is outside 1-247"),
            std::string::npos);
  EXPECT_NE(errorOf("role: slave").find("slave_id"), std::string::npos);
  EXPECT_NE(errorOf("role: slave\nslave_id: 1\ncoil: 70000").find("coil: 70000 is outside 0-10000"),
            std::string::npos);
  EXPECT_NE(
      errorOf("role: slave\nslave_id: 1\ncoil: 8\nnames: {coil: {9: x}}").find("names/coil/9"),
      std::string::npos);
  EXPECT_NE(errorOf("role: slave\nslave_id: 1\nnames: {coil: {1: 2bad}}").find("2bad"),
            std::string::npos);
  // The keys of earlier versions are refused, pointing at the table's one name.
  EXPECT_EQ(errorOf("role: slave\nslave_id: 1\nholding_registers: 8"),
            "holding_registers: the table is now named 'holding_register'");
  EXPECT_EQ(errorOf("role: slave\nslave_id: 1\nnames: {coils: {1: x}}"),
            "names/coils: the table is now named 'coil'");
  EXPECT_NE(errorOf("role: slave\nslave_id: 1\ndevices: {}").find("devices"), std::string::npos);
  EXPECT_NE(errorOf("role: slave\nslave_id: 1\nbaud: 7").find("baud"), std::string::npos);
}
