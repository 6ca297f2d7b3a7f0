// The simulators' command lines (CLI11), parsed the same way: roslaunch's own arguments
// (__name:=..., remappings) are accepted and ignored; anything else unknown is an error shown
// with the help, exit code 2.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

namespace modbus_rtu_driver {

// "<program>: <why>" and the help on stderr; returns the exit code 2.
inline int commandLineError(const CLI::App& app, const std::string& why) {
  std::fprintf(stderr, "%s: %s\n%s", app.get_name().c_str(), why.c_str(), app.help().c_str());
  return 2;
}

// Parses argv into `app` (built with allow_extras()). -1: go on; otherwise the exit code (0
// after --help).
inline int parseCommandLine(CLI::App& app, int argc, char** argv) {
  std::vector<std::string> ros_arguments;
  app.add_option("ros_arguments", ros_arguments)->group("");  // roslaunch's, ignored
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::printf("%s", app.help().c_str());
    return 0;
  } catch (const CLI::ParseError& e) {
    return commandLineError(app, e.what());
  }
  for (const std::string& extra : app.remaining())
    return commandLineError(
        app, (extra.rfind('-', 0) == 0 ? "unknown option " : "unexpected argument ") + extra);
  for (const std::string& word : ros_arguments) {
    const bool ros =
        word.empty() || word.rfind("__", 0) == 0 || word.find(":=") != std::string::npos;
    if (!ros) return commandLineError(app, "unexpected argument " + word);
  }
  return -1;
}

}  // namespace modbus_rtu_driver
