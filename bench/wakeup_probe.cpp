// The machine's share, measured apart from the driver: a bare thread that sleeps to a deadline
// every --period-us and wakes, as the bus thread does for its gaps. bench/line_attribution.py
// runs it beside the node (how late the machine wakes a thread that does nothing), and
// bench/node_bench.py alone at the bus thread's wake-up rate (what sleeping and waking that
// often costs here, whatever the thread does). Prints one JSON object:
// {"wakeups": N, "late_us": {"p50": .., "p99": .., "max": ..}, "cpu_percent": ..,
//  "policy": "SCHED_FIFO 50" | "SCHED_OTHER" | "SCHED_OTHER (SCHED_FIFO refused: ...)"}.
//   modbus_rtu_wakeup_probe [--period-us 1750] [--seconds 5] [--fifo PRIORITY]
#include <sys/prctl.h>
#include <sys/resource.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/realtime.h"

namespace {

int64_t nanoseconds(const timespec& t) {
  return static_cast<int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}

timespec fromNanoseconds(int64_t ns) {
  return timespec{static_cast<time_t>(ns / 1000000000), static_cast<long>(ns % 1000000000)};
}

double cpuSeconds() {
  rusage r{};
  getrusage(RUSAGE_SELF, &r);
  return static_cast<double>(r.ru_utime.tv_sec + r.ru_stime.tv_sec) +
         static_cast<double>(r.ru_utime.tv_usec + r.ru_stime.tv_usec) * 1e-6;
}

double percentile(std::vector<double> v, double p) {  // as node_bench.py's
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto index =
      static_cast<size_t>(std::lround(p / 100.0 * static_cast<double>(v.size() - 1)));
  return v[std::min(v.size() - 1, index)];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"A bare thread's wake-up lateness and the CPU its sleeping costs"};
  int period_us = 1750;  // t3.5 above 19200 baud
  double seconds = 5;
  int fifo = 0;
  app.add_option("--period-us", period_us, "sleep to a deadline this often [us]")
      ->check(CLI::Range(50, 1000000));
  app.add_option("--seconds", seconds, "how long [s]")->check(CLI::Range(0.1, 3600.0));
  app.add_option("--fifo", fifo, "SCHED_FIFO priority, as the node's realtime_priority (0: not)")
      ->check(CLI::Range(0, 99));
  CLI11_PARSE(app, argc, argv);

  std::string policy = "SCHED_OTHER";
  if (fifo > 0) {
    std::string error;
    policy = modbus_rtu_driver::raiseToRealtime(fifo, &error) ? "SCHED_FIFO " + std::to_string(fifo)
                                                              : "SCHED_OTHER (" + error + ")";
  }
  prctl(PR_SET_TIMERSLACK, 1000UL, 0, 0, 0);  // as the bus thread's keepGap
  std::vector<double> late_us;
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  const int64_t start = nanoseconds(now);
  const int64_t end = start + static_cast<int64_t>(seconds * 1e9);
  const int64_t period = static_cast<int64_t>(period_us) * 1000;
  const double cpu_before = cpuSeconds();
  for (int64_t deadline = start + period; deadline < end; deadline += period) {
    const timespec at = fromNanoseconds(deadline);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) != 0) {
    }
    clock_gettime(CLOCK_MONOTONIC, &now);
    // A wake-up later than a whole period skips the deadlines it missed, as a late bus thread
    // would not send twice.
    late_us.push_back(static_cast<double>(nanoseconds(now) - deadline) * 1e-3);
    deadline = std::max(deadline, nanoseconds(now) - period);
  }
  clock_gettime(CLOCK_MONOTONIC, &now);
  const double wall = static_cast<double>(nanoseconds(now) - start) * 1e-9;
  nlohmann::json out;
  out["wakeups"] = late_us.size();
  out["late_us"] = {
      {"p50", percentile(late_us, 50)},
      {"p99", percentile(late_us, 99)},
      {"max", late_us.empty() ? 0.0 : *std::max_element(late_us.begin(), late_us.end())}};
  out["cpu_percent"] = 100.0 * (cpuSeconds() - cpu_before) / wall;
  out["policy"] = policy;
  std::printf("%s\n", out.dump().c_str());
  return 0;
}
