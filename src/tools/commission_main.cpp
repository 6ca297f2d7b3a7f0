// modbus_rtu_commission: scan for and configure Modbus RTU boards (no ROS master needed).
#include <unistd.h>

#include <csignal>
#include <iostream>

#include "modbus_rtu_driver/tools/commission.h"
#include "modbus_rtu_driver/tools/commission_output.h"

namespace {

std::atomic<bool> g_stop{false};

// The first Ctrl-C ends a scan or watch early (what was found is still printed) and makes a
// pending confirmation read fail; a second one ends the program at once.
void onInterrupt(int) {
  if (g_stop.exchange(true)) {
    std::signal(SIGINT, SIG_DFL);
    std::raise(SIGINT);
  }
}

void installInterruptHandler() {
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a blocked read of the answer returns
  sigaction(SIGINT, &action, nullptr);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace modbus_rtu_driver;
  CommissionCommand command;
  std::string error;
  if (!parseCommission(std::vector<std::string>(argv + 1, argv + argc), &command, &error)) {
    Output(command.json, std::cout, std::cerr).fail(kExitBadArguments, error);
    std::cerr << "(modbus_rtu_commission --help lists the commands and ranges)\n";
    return kExitBadArguments;
  }
  if (!command.help.empty()) {
    std::cout << command.help;
    return kExitOk;
  }
  installInterruptHandler();
  const CommissionIo io{std::cin, std::cout, std::cerr, g_stop, isatty(STDERR_FILENO) == 1};
  return runCommission(command, io);
}
