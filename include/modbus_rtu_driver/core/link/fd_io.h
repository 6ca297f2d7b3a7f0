// Waiting on and reading from a descriptor (a serial port or a socket), shared by the serial
// link and the TCP transports so there is one reader by announced length.
#pragma once

#include <chrono>
#include <functional>

#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

// 1 when `fd` is readable (or closed/failed: the read tells), 0 after `seconds`, -1 on error
// (errno set). An interrupted wait resumes with the time left.
int waitReadable(int fd, double seconds);

enum class ReadStatus { kComplete, kTimeout, kClosed, kError, kBadHeader };

// When the first and the last byte of a frame were read (CLOCK_MONOTONIC).
struct ReadTimes {
  std::chrono::steady_clock::time_point first{}, last{};
};

// Reads one frame into `out`: the first byte within `first` s, each later one within `between`
// s, and stops as soon as `length_of(bytes so far)` (0 = cannot tell yet, < 0 = not a frame)
// says it is whole; never more than `max_length` bytes. Until the length is known it asks for
// at most `shortest` bytes (the shortest frame there is), so it never reads into the next frame
// and needs few reads. `error` gets errno on kError; `times`, when given, when bytes came.
ReadStatus readFrame(int fd, double first, double between,
                     const std::function<long(const Bytes&)>& length_of, size_t shortest,
                     size_t max_length, Bytes* out, int* error, ReadTimes* times = nullptr);

}  // namespace modbus_rtu_driver
