// Allocations on the poll path (issue 50: none that is not needed in the steady state), counted
// with this test's own global operator new: encoding a read's request is one allocation (its
// frame), decoding the reply one (the values the caller gets), reading the reply none once the
// link's buffer has its capacity. Each was several before (a vector grown byte by byte, the
// values copied into the result).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "modbus_rtu_driver/core/link/fd_io.h"
#include "modbus_rtu_driver/core/modbus/frame.h"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

// Every form of new and delete but the aligned ones is replaced, so that what one allocates the
// other frees: a sanitizer's build otherwise pairs its own nothrow or array new (libstdc++'s
// temporary buffers use nothrow new) with this free, and reports the mismatch (Debian 13, clang
// 19's AddressSanitizer).
void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, const std::nothrow_t& /*tag*/) noexcept {
  ++g_allocations;
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}
void operator delete(void* p, const std::nothrow_t& /*tag*/) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t /*size*/) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t& /*tag*/) noexcept {
  std::free(p);
}

using namespace modbus_rtu_driver;

namespace {

// The allocations `f` makes.
template <typename F>
long allocationsOf(F&& f) {
  const long before = g_allocations.load();
  f();
  return g_allocations.load() - before;
}

}  // namespace

TEST(PollAllocations, EncodingAReadIsOneAllocation) {
  for (const Request& read : {Request::readCoils(8, 0, 8), Request::readHoldingRegisters(1, 0, 24),
                              Request::readInputRegisters(2, 0x100, 10)}) {
    std::optional<EncodedRequest> encoded;
    EXPECT_EQ(allocationsOf([&] { encoded = EncodedRequest::encode(read); }), 1) << read.describe();
    ASSERT_TRUE(encoded);
  }
}

TEST(PollAllocations, DecodingAReadsReplyIsOneAllocation) {
  const auto coils = EncodedRequest::encode(Request::readCoils(8, 0, 8));
  const auto registers = EncodedRequest::encode(Request::readHoldingRegisters(1, 0, 3));
  ASSERT_TRUE(coils && registers);
  Bytes coil_reply{8, 0x01, 0x01, 0xA5};
  appendCrc(coil_reply);
  Bytes register_reply{1, 0x03, 0x06, 0, 1, 0, 2, 0, 3};
  appendCrc(register_reply);
  Result r;
  EXPECT_EQ(allocationsOf([&] { r = decodeReply(*coils, coil_reply); }), 1);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, (std::vector<uint16_t>{1, 0, 1, 0, 0, 1, 0, 1}));
  EXPECT_EQ(allocationsOf([&] { r = decodeReply(*registers, register_reply); }), 1);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, (std::vector<uint16_t>{1, 2, 3}));
}

// The link reads every reply into one buffer of its own (Link::readRtuReply): with its capacity
// there, a reply read in several pieces allocates nothing.
TEST(PollAllocations, ReadingAReplyIntoAKeptBufferAllocatesNothing) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  Bytes reply{1, 0x03, 0x06, 0, 1, 0, 2, 0, 3};
  appendCrc(reply);
  Bytes buffer;
  buffer.reserve(kMaxAduLength);
  const auto length_of = [](const Bytes& b) { return b.size() < 3 ? 0L : 5L + b[2]; };
  const std::function<long(const Bytes&)> length(length_of);
  for (int round = 0; round < 3; ++round) {
    ASSERT_EQ(write(fds[1], reply.data(), 4), 4);  // in two pieces, as a serial port gives them
    ASSERT_EQ(write(fds[1], reply.data() + 4, reply.size() - 4),
              static_cast<ssize_t>(reply.size() - 4));
    ReadStatus status = ReadStatus::kError;
    EXPECT_EQ(allocationsOf([&] {
                status = readFrame(fds[0], 1.0, 1.0, length, 5, kMaxAduLength, &buffer, nullptr);
              }),
              0);
    EXPECT_EQ(status, ReadStatus::kComplete);
    EXPECT_EQ(buffer, reply);
  }
  close(fds[0]);
  close(fds[1]);
}
