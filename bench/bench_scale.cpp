// Scale: 1-32 simulated PDUs on one paced 115200 line, polled through the real core path
// (device classes, BusScheduler, RtuLink) faster than the line can carry; aggregate polls per
// second against the line's limit, then the same with one device silenced (offline).
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/config/device_types/yespeed_pdu.h"
#include "modbus_rtu_driver/core/link/rtu_link.h"
#include "modbus_rtu_driver/devices/registry.h"
#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

namespace {

struct Outcome {
  double polls_per_s = 0;      // by the devices that answer
  double fairness = 0;         // fewest polls of an answering device / most
  double tx_per_s = 0;         // successful transactions
  bool overrun = false;        // the scheduler says the configured rate cannot be kept
  uint64_t offline_tries = 0;  // transactions spent on the offline device
};

// Line time of one PDU poll: FC01 8 relays (8 + 6 bytes) and FC04 5 registers (8 + 15 bytes),
// each with t3.5 after the request and after the reply.
double pollWireTime(const LinkConfig& c) {
  return (8 + 6 + 8 + 15) * characterTime(c) + 4 * frameGap(c);
}

Outcome run(const std::string& dir, int devices, bool one_offline, double seconds,
            double warm_up_seconds) {
  SimulatorConfig config;
  config.factory.baud = 115200;
  config.pace = true;
  for (int a = 1; a <= devices; ++a) config.devices.push_back({kYespeedPduType.name, a});
  SimulatorOptions options;
  options.link = dir + "/scale" + std::to_string(devices) + (one_offline ? "off" : "");
  Simulator sim(config, options);
  std::string error;
  if (!sim.start(&error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return {};
  }
  if (one_offline) sim.command("silence 1 1");
  LinkConfig lc;
  lc.port = options.link;
  lc.baud = 115200;
  RtuLink link(lc);
  BusScheduler scheduler(link);
  std::vector<std::shared_ptr<Device>> pdus;
  for (int a = 1; a <= devices; ++a) {
    DeviceConfig dc;
    dc.name = "pdu" + std::to_string(a);
    dc.type = kYespeedPduType.name;
    dc.address = a;
    std::shared_ptr<Device> d = createDevice(dc);
    scheduler.addDevice(dc.name);
    scheduler.addPoll(
        dc.name, 1000.0, [d](Transport& t) { return d->poll(t); }, nullptr);
    pdus.push_back(d);
  }
  scheduler.start();
  // Warm-up: first polls read the limits too; an offline device reaches its probing backoff.
  std::this_thread::sleep_for(std::chrono::duration<double>(warm_up_seconds));
  auto polls = [&] {
    uint64_t n = 0;
    for (const auto& d : pdus) n += scheduler.health(d->name()).polls_ok;
    return n;
  };
  std::vector<uint64_t> each0;
  each0.reserve(pdus.size());
  for (const auto& d : pdus) each0.push_back(scheduler.health(d->name()).polls_ok);
  const uint64_t polls0 = polls(), ok0 = link.stats().ok, tries0 = link.stats().timeouts;
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  Outcome o;
  o.polls_per_s = static_cast<double>(polls() - polls0) / seconds;
  o.tx_per_s = static_cast<double>(link.stats().ok - ok0) / seconds;
  o.offline_tries = link.stats().timeouts - tries0;
  uint64_t least = UINT64_MAX, most = 0;
  for (size_t i = one_offline ? 1 : 0; i < pdus.size(); ++i) {
    const DeviceHealth h = scheduler.health(pdus[i]->name());
    least = std::min(least, h.polls_ok - each0[i]);
    most = std::max(most, h.polls_ok - each0[i]);
  }
  o.fairness = most ? static_cast<double>(least) / static_cast<double>(most) : 0.0;
  for (const auto& d : pdus) o.overrun = o.overrun || scheduler.health(d->name()).rate_overrun;
  scheduler.stop();
  return o;
}

}  // namespace

void benchmarkScale(const std::string& dir, double seconds, double warm_up_seconds,
                    std::ofstream& csv) {
  LinkConfig lc;
  lc.baud = 115200;
  const double limit = 1.0 / pollWireTime(lc);
  std::printf(
      "## Scale (PDUs on one paced 115200 line, each asking for 1000 polls/s; a poll is FC01 + "
      "FC04, line limit %.1f polls/s)\n\n",
      limit);
  std::printf(
      "| devices | polls/s | transactions/s | of the line limit | fewest / most polls of a device "
      "| overrun reported | one offline: polls/s of the others | of the limit | timeouts/s on "
      "the offline one |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (int n : {1, 4, 16, 32}) {
    const Outcome all = run(dir, n, false, seconds, warm_up_seconds);
    Outcome off;
    if (n > 1) off = run(dir, n, true, seconds, warm_up_seconds);
    std::printf("| %d | %.1f | %.1f | %.1f %% | %.2f | %s |", n, all.polls_per_s, all.tx_per_s,
                100.0 * all.polls_per_s / limit, all.fairness, all.overrun ? "yes" : "no");
    if (n > 1)
      std::printf(" %.1f | %.1f %% | %.2f |\n", off.polls_per_s, 100.0 * off.polls_per_s / limit,
                  static_cast<double>(off.offline_tries) / seconds);
    else
      std::printf(" - | - | - |\n");
    csv << "scale," << n << "," << all.polls_per_s << "," << off.polls_per_s << ","
        << all.polls_per_s / limit << "\n";
  }
  std::printf(
      "\nEvery device asks for more than the line carries, so the bus is shared in turn (fewest / "
      "most polls of one device near 1) and each reports the overrun in /diagnostics. An offline "
      "device is probed with backoff (0.5 s doubling to 5 s); a probe costs two response "
      "timeouts (a try and a retry).\n\n");
}

}  // namespace modbus_rtu_driver
