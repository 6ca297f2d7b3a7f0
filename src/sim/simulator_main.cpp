// modbus_rtu_simulator: Modbus RTU devices on a pseudo-terminal (ROS-free).
//   modbus_rtu_simulator --config FILE --link PATH [--control SOCKET] [--state-file FILE]
//                        [--pace] [--verbose]
// SIGHUP power-cycles the devices; SIGINT / SIGTERM stop it. roslaunch's __name:= style
// arguments are ignored.
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

#include "modbus_rtu_driver/sim/simulator.h"

namespace {
volatile std::sig_atomic_t g_stop = 0;
volatile std::sig_atomic_t g_power_cycle = 0;

int usage(const char* why) {
  std::fprintf(stderr,
               "%s\nusage: modbus_rtu_simulator --config FILE --link PATH [--control SOCKET] "
               "[--state-file FILE] [--pace] [--verbose]\n",
               why);
  return 2;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace modbus_rtu_driver;
  std::string config_path;
  SimulatorOptions options;
  bool pace = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--config")
      config_path = value();
    else if (a == "--link")
      options.link = value();
    else if (a == "--control")
      options.control = value();
    else if (a == "--state-file")
      options.state_file = value();
    else if (a == "--pace")
      pace = true;
    else if (a == "--verbose")
      options.verbose = true;
    else if (a.rfind("__", 0) == 0 || a.find(":=") != std::string::npos)
      continue;  // roslaunch
    else
      return usage(("unknown option " + a).c_str());
  }
  if (config_path.empty() || options.link.empty()) return usage("--config and --link are needed");
  SimulatorConfig config;
  std::string error;
  if (!loadSimulatorConfig(config_path, &config, &error)) {
    std::fprintf(stderr, "%s: %s\n", config_path.c_str(), error.c_str());
    return 1;
  }
  config.pace = config.pace || pace;
  Simulator sim(config, options);
  if (!sim.start(&error)) {
    std::fprintf(stderr, "simulator: %s\n", error.c_str());
    return 1;
  }
  std::signal(SIGINT, [](int) { g_stop = 1; });
  std::signal(SIGTERM, [](int) { g_stop = 1; });
  std::signal(SIGHUP, [](int) { g_power_cycle = 1; });
  std::printf("simulator ready on %s (%s)\n", options.link.c_str(), sim.command("info").c_str());
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
