// modbus_rtu_commission: scan for and configure Modbus RTU boards (no ROS master needed).
#include <csignal>
#include <iostream>

#include "modbus_rtu_driver/tools/commission.h"

namespace {
std::atomic<bool> g_stop{false};
}

int main(int argc, char** argv) {
  using namespace modbus_rtu_driver;
  std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& a : args)
    if (a == "--help" || a == "-h") {
      std::cout << commissionUsage();
      return 0;
    }
  CommissionCommand command;
  std::string error;
  if (!parseCommission(args, &command, &error)) {
    std::cerr << "error: " << error << "\n" << commissionUsage();
    return kExitBadArguments;
  }
  std::signal(SIGINT, [](int) { g_stop = true; });  // ends a scan or watch early
  return runCommission(command, std::cin, std::cout, std::cerr, g_stop);
}
