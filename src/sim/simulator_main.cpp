// modbus_rtu_simulator: Modbus RTU devices on a pseudo-terminal (ROS-free).
// Prints "simulator ready on <link>" once the link exists; SIGHUP power-cycles the devices;
// SIGTERM stops it and removes the link and the control socket, and so does SIGINT, but only once
// no program holds the link's port: Ctrl-C in a terminal, and roslaunch stopping a launch, signal
// the bus node at the same time, and its shutdown safe writes still need the line (a second
// SIGINT stops it at once). roslaunch's __name:= style arguments are ignored.
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/sim/command_line.h"
#include "modbus_rtu_driver/sim/simulator.h"
#include "modbus_rtu_driver/sim/simulator_tcp.h"

namespace {

volatile std::sig_atomic_t g_interrupts = 0;  // SIGINTs
volatile std::sig_atomic_t g_terminate = 0;   // SIGTERM
volatile std::sig_atomic_t g_power_cycle = 0;

// How long a SIGINT waits at most for the program on the link to let go of it: roslaunch sends
// SIGTERM 15 s after its SIGINT anyway, and a bus node's stop takes at most about 13 s.
constexpr std::chrono::seconds kLingerLimit{20};

void onSignal(int sig) {
  if (sig == SIGHUP)
    g_power_cycle = 1;
  else if (sig == SIGINT)
    g_interrupts = g_interrupts + 1;
  else
    g_terminate = 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace modbus_rtu_driver;
  std::string config_path;
  SimulatorOptions options;
  bool pace = false;
  std::string tcp;
  CLI::App app(
      "Modbus RTU devices on a pseudo-terminal; prints \"simulator ready on PATH\" once "
      "the link exists.",
      "modbus_rtu_simulator");
  app.footer(
      "SIGHUP power-cycles the devices; SIGTERM stops the simulator, and so does SIGINT once no "
      "program holds the link's port (a second SIGINT: at once).");
  app.allow_extras();
  app.add_option("--config", config_path,
                 "devices and line settings (see config/simulator.yaml); needed")
      ->type_name("FILE");
  app.add_option("--link", options.link,
                 "symlink to the pty's slave side (a stale link is replaced); needed")
      ->type_name("PATH");
  app.add_option("--state-file", options.state_file,
                 "what the devices store (address, baud, parity, ...), loaded at start")
      ->type_name("FILE");
  app.add_option("--control", options.control, "Unix socket for test commands (default: PATH.ctl)")
      ->type_name("SOCKET");
  app.add_option("--rtu-tcp", options.rtu_tcp_port,
                 "also serve the line as a transparent RTU-over-TCP gateway on 127.0.0.1:PORT")
      ->type_name("PORT")
      ->check(CLI::Range(1, 65535));
  app.add_option("--tcp", tcp,
                 "also serve the devices over Modbus TCP at HOST:PORT (a gateway on the line)")
      ->type_name("HOST:PORT");
  app.add_flag("--pace", pace, "the line runs at its real speed (also `pace: true` in the config)");
  app.add_flag("--verbose", options.verbose,
               "print every frame: rx/tx followed by the bytes in hex");
  app.add_flag("--timestamps", options.timestamps,
               "with --verbose: CLOCK_MONOTONIC seconds of the frame's first and last byte after "
               "rx/tx");
  if (const int code = parseCommandLine(app, argc, argv); code >= 0) return code;
  if (config_path.empty() || options.link.empty())
    return commandLineError(app, "--config and --link are needed");
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
  SimulatorTcp gateway(config, options.link);
  if (!tcp.empty() && !gateway.start(tcp, &error)) {
    std::fprintf(stderr, "modbus_rtu_simulator: --tcp %s: %s\n", tcp.c_str(), error.c_str());
    return 1;
  }
  const std::string info = sim.command("info");
  std::fprintf(
      stderr, "modbus_rtu_simulator: devices%s; control socket %s%s%s\n", info.substr(2).c_str(),
      sim.controlPath().c_str(), config.pace ? "; pacing the line" : "",
      sim.rtuTcpPort() ? ("; rtu+tcp://127.0.0.1:" + std::to_string(sim.rtuTcpPort())).c_str()
                       : "");
  if (!tcp.empty())
    std::fprintf(stderr, "modbus_rtu_simulator: Modbus TCP on port %u\n", gateway.port());
  std::printf("simulator ready on %s\n", options.link.c_str());
  std::fflush(stdout);
  auto serve = [&sim] {
    if (g_power_cycle) {
      g_power_cycle = 0;
      sim.requestPowerCycle();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  };
  while (!g_terminate && g_interrupts == 0) serve();
  if (!g_terminate && g_interrupts == 1 && sim.linkClaimed()) {
    std::fprintf(stderr,
                 "modbus_rtu_simulator: stopping once the program on %s closes it (SIGINT again "
                 "or SIGTERM: at once)\n",
                 options.link.c_str());
    const auto limit = std::chrono::steady_clock::now() + kLingerLimit;
    while (!g_terminate && g_interrupts == 1 && sim.linkClaimed() &&
           std::chrono::steady_clock::now() < limit)
      serve();
  }
  gateway.stop();
  sim.stop();
  return 0;
}
