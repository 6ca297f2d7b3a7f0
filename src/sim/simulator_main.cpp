// modbus_rtu_simulator: Modbus RTU devices on a pseudo-terminal (ROS-free).
// Prints "simulator ready on <link>" once the link exists; SIGHUP power-cycles the devices;
// SIGINT / SIGTERM stop it and remove the link and the control socket. roslaunch's
// __name:= style arguments are ignored.
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

#include "modbus_rtu_driver/sim/simulator.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;
volatile std::sig_atomic_t g_power_cycle = 0;

const char* kUsage =
    "usage: modbus_rtu_simulator --config FILE --link PATH [--state-file FILE]\n"
    "                            [--control SOCKET] [--pace] [--verbose [--timestamps]]\n"
    "  --config FILE      devices and line settings (see config/simulator.yaml)\n"
    "  --link PATH        symlink to the pty's slave side (a stale link is replaced)\n"
    "  --state-file FILE  what the devices store (address, baud, parity, ...), loaded at start\n"
    "  --control SOCKET   Unix socket for test commands (default: PATH.ctl)\n"
    "  --pace             the line runs at its real speed (also `pace: true` in the config)\n"
    "  --verbose          print every frame: rx/tx followed by the bytes in hex\n"
    "  --timestamps       with --verbose: CLOCK_MONOTONIC seconds after rx/tx\n"
    "SIGHUP power-cycles the devices; SIGINT/SIGTERM stop the simulator.\n";

int usage(const std::string& why) {
  std::fprintf(stderr, "modbus_rtu_simulator: %s\n%s", why.c_str(), kUsage);
  return 2;
}

void onSignal(int sig) {
  if (sig == SIGHUP)
    g_power_cycle = 1;
  else
    g_stop = 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace modbus_rtu_driver;
  std::string config_path;
  SimulatorOptions options;
  bool pace = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool takes_value =
        a == "--config" || a == "--link" || a == "--control" || a == "--state-file";
    if (takes_value && i + 1 >= argc) return usage(a + ": missing value");
    if (a == "--config")
      config_path = argv[++i];
    else if (a == "--link")
      options.link = argv[++i];
    else if (a == "--control")
      options.control = argv[++i];
    else if (a == "--state-file")
      options.state_file = argv[++i];
    else if (a == "--pace")
      pace = true;
    else if (a == "--verbose")
      options.verbose = true;
    else if (a == "--timestamps")
      options.timestamps = true;
    else if (a == "--help" || a == "-h")
      return std::printf("%s", kUsage), 0;
    else if (a.rfind("__", 0) == 0 || a.find(":=") != std::string::npos || a.empty())
      continue;  // roslaunch
    else
      return usage("unknown option " + a);
  }
  if (config_path.empty() || options.link.empty()) return usage("--config and --link are needed");
  SimulatorConfig config;
  std::string error;
  if (!loadSimulatorConfig(config_path, &config, &error)) {
    std::fprintf(stderr, "modbus_rtu_simulator: %s: %s\n", config_path.c_str(), error.c_str());
    return 1;
  }
  config.pace = config.pace || pace;

  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);

  Simulator sim(config, options);
  if (!sim.start(&error)) {
    std::fprintf(stderr, "modbus_rtu_simulator: %s\n", error.c_str());
    return 1;
  }
  const std::string info = sim.command("info");
  std::fprintf(stderr, "modbus_rtu_simulator: devices%s; control socket %s%s\n",
               info.substr(2).c_str(), sim.controlPath().c_str(),
               config.pace ? "; pacing the line" : "");
  std::printf("simulator ready on %s\n", options.link.c_str());
  std::fflush(stdout);
  while (!g_stop) {
    if (g_power_cycle) {
      g_power_cycle = 0;
      sim.requestPowerCycle();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  sim.stop();
  return 0;
}
