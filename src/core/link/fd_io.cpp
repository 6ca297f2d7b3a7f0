#include "modbus_rtu_driver/core/link/fd_io.h"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>

namespace modbus_rtu_driver {

int waitReadable(int fd, double seconds) {
  using Steady = std::chrono::steady_clock;
  const auto until = Steady::now() + std::chrono::duration_cast<Steady::duration>(
                                         std::chrono::duration<double>(std::max(seconds, 0.0)));
  for (;;) {
    const double left = std::chrono::duration<double>(until - Steady::now()).count();
    const timespec wait{
        static_cast<time_t>(std::max(left, 0.0)),
        static_cast<long>((std::max(left, 0.0) - std::floor(std::max(left, 0.0))) * 1e9)};
    pollfd p{fd, POLLIN, 0};
    const int ready = ppoll(&p, 1, &wait, nullptr);
    if (ready == -1 && errno == EINTR) continue;
    return ready < 0 ? -1 : ready > 0 ? 1 : 0;
  }
}

ReadStatus readFrame(int fd, double first, double between,
                     const std::function<long(const Bytes&)>& length_of, size_t shortest,
                     size_t max_length, Bytes* out, int* error, ReadTimes* times) {
  out->clear();
  size_t need = 0;
  while (need == 0 || out->size() < need) {
    const int ready = waitReadable(fd, out->empty() ? first : between);
    if (ready == 0) return ReadStatus::kTimeout;
    if (ready < 0) {
      if (error) *error = errno;
      return ReadStatus::kError;
    }
    uint8_t chunk[512];
    const size_t want =
        need ? need - out->size() : std::max<size_t>(1, shortest - std::min(shortest, out->size()));
    const ssize_t n = read(fd, chunk, std::min(sizeof chunk, want));
    if (n == 0) return ReadStatus::kClosed;
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      if (error) *error = errno;
      return errno == ECONNRESET ? ReadStatus::kClosed : ReadStatus::kError;
    }
    if (times) {
      times->last = std::chrono::steady_clock::now();
      if (out->empty()) times->first = times->last;
    }
    out->insert(out->end(), chunk, chunk + n);
    const long length = length_of(*out);
    if (length < 0) return ReadStatus::kBadHeader;
    need = std::min(static_cast<size_t>(length), max_length);
  }
  return ReadStatus::kComplete;
}

}  // namespace modbus_rtu_driver
