// modbus_rtu_dm500_sim: plays the DM500 controller (a Modbus master) on a pty (ROS-free).
//   modbus_rtu_dm500_sim --link PATH --script FILE [--report FILE] [--baud B] [--timeout S]
// Exit code 0 when every step passed. roslaunch's __name:= style arguments are ignored.
#include <cstdio>
#include <fstream>
#include <string>

#include "modbus_rtu_driver/sim/dm500_master.h"

int main(int argc, char** argv) {
  using namespace modbus_rtu_driver;
  std::string link, script, report;
  int baud = 9600;
  double timeout = 0.5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--link")
      link = value();
    else if (a == "--script")
      script = value();
    else if (a == "--report")
      report = value();
    else if (a == "--baud")
      baud = std::stoi(value());
    else if (a == "--timeout")
      timeout = std::stod(value());
    else if (a.rfind("__", 0) == 0 || a.find(":=") != std::string::npos)
      continue;
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  std::ifstream steps(script);
  if (link.empty() || !steps) {
    std::fprintf(stderr, "usage: modbus_rtu_dm500_sim --link PATH --script FILE [--report FILE]\n");
    return 2;
  }
  if (!report.empty()) std::remove(report.c_str());  // a report is only there once this run ends
  PtyLink pty;
  std::string error;
  if (!pty.open(link, baud, &error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  std::printf("master ready on %s\n", link.c_str());
  std::fflush(stdout);
  Dm500Master master(pty, timeout);
  std::string results;
  int passed = 0, failed = 0, number = 0;
  for (std::string line; std::getline(steps, line);) {
    ++number;
    if (line.find_first_not_of(" \t") == std::string::npos ||
        line[line.find_first_not_of(" \t")] == '#')
      continue;
    std::string why;
    const bool ok = master.step(line, &why);
    const std::string out =
        (ok ? "PASS " : "FAIL ") + std::to_string(number) + ": " + line + (ok ? "" : " -- " + why);
    std::printf("%s\n", out.c_str());
    std::fflush(stdout);
    results += out + "\n";
    (ok ? passed : failed)++;
  }
  results += std::to_string(passed) + " passed, " + std::to_string(failed) + " failed\n";
  std::printf("%d passed, %d failed\n", passed, failed);
  if (!report.empty()) std::ofstream(report) << results;
  return failed == 0 ? 0 : 1;
}
