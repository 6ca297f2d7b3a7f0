// modbus_rtu_dm500_sim: plays the DM500 controller (a Modbus master) on a pty (ROS-free).
//   modbus_rtu_dm500_sim --link PATH --script FILE [--report FILE] [--baud B] [--timeout S]
// (CLI11; --help lists the options and their ranges.)
// Exit code 0 when every step passed. roslaunch's __name:= style arguments are ignored.
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/sim/command_line.h"
#include "modbus_rtu_driver/sim/dm500_master.h"

int main(int argc, char** argv) {
  using namespace modbus_rtu_driver;
  std::string link, script, report;
  int baud = 9600;
  double timeout = 0.5;
  CLI::App app(
      "Plays the DM500 controller (a Modbus master) on a pty: one step of the script "
      "per line. Exit code 0 when every step passed.",
      "modbus_rtu_dm500_sim");
  app.allow_extras();
  app.add_option("--link", link, "where to create the pty's symlink; needed")->type_name("PATH");
  app.add_option("--script", script, "the steps (see test/rostest/dm500.script); needed")
      ->type_name("FILE");
  app.add_option("--report", report, "PASS/FAIL lines and the totals, written at the end")
      ->type_name("FILE");
  app.add_option("--baud", baud, "line speed (default 9600)")
      ->type_name("B")
      ->check(
          CLI::IsMember(std::vector<int>(std::begin(kStandardBauds), std::end(kStandardBauds))));
  app.add_option("--timeout", timeout, "wait for each reply in s (default 0.5)")
      ->type_name("S")
      ->check(CLI::Range(0.001, 60.0));
  if (const int code = parseCommandLine(app, argc, argv); code >= 0) return code;
  if (link.empty() || script.empty())
    return commandLineError(app, "--link and --script are needed");
  std::ifstream steps(script);
  if (!steps) return commandLineError(app, "--script: cannot read " + script);
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
