// modbus_rtu_benchmark: this package's bus layer against a plain libmodbus loop and a pymodbus
// client, achieved transactions per second against the line's theoretical limit, 1-32 devices
// on one line, all against the simulator on a pty, and the TCP transports against plain
// libmodbus TCP (bench_transports.cpp), in one run. Prints markdown tables and writes CSV; figures
// are ratios for a noisy machine. (Node latency and CPU: node_bench.py.)
//   modbus_rtu_benchmark [--seconds S] [--csv FILE] [--pymodbus CLIENT_SCRIPT]
#include <modbus/modbus.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bench_common.h"
#include "modbus_rtu_driver/core/config/device_types/yespeed_pdu.h"
#include "modbus_rtu_driver/core/link/rtu_link.h"
#include "modbus_rtu_driver/sim/simulator.h"

using namespace modbus_rtu_driver;
using Steady = std::chrono::steady_clock;

namespace {

struct Op {
  const char* name;
  Request request;
};

// Transactions per second of Debian's pymodbus per function code ("01" -> rate), from
// bench/pymodbus_client.py run against `port`; empty when it could not run.
std::map<std::string, double> pymodbusRates(const std::string& script, const std::string& port,
                                            double seconds) {
  std::map<std::string, double> rates;
  const std::string cmd =
      "/usr/bin/python3 '" + script + "' '" + port + "' 2 " + std::to_string(seconds);
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return rates;
  char code[8];
  double rate = 0;
  while (std::fscanf(p, "%7s %lf", code, &rate) == 2) rates[code] = rate;
  pclose(p);
  return rates;
}

}  // namespace

namespace modbus_rtu_driver {

double transactionRate(double seconds, const std::function<bool()>& once) {
  const auto end = Steady::now() + std::chrono::duration<double>(seconds);
  long n = 0;
  const auto start = Steady::now();
  while (Steady::now() < end) {
    if (!once()) return 0;
    ++n;
  }
  return n / std::chrono::duration<double>(Steady::now() - start).count();
}

bool plainLibmodbus(modbus_t* ctx, const Request& r) {
  uint8_t bits[16];
  uint16_t regs[16];
  switch (r.function) {
    case FunctionCode::kReadCoils:
      return modbus_read_bits(ctx, r.address, r.count, bits) == r.count;
    case FunctionCode::kReadHoldingRegisters:
      return modbus_read_registers(ctx, r.address, r.count, regs) == r.count;
    case FunctionCode::kReadInputRegisters:
      return modbus_read_input_registers(ctx, r.address, r.count, regs) == r.count;
    case FunctionCode::kWriteSingleCoil:
      return modbus_write_bit(ctx, r.address, r.values[0]) == 1;
    case FunctionCode::kWriteMultipleCoils:
      for (size_t i = 0; i < r.values.size(); ++i) bits[i] = static_cast<uint8_t>(r.values[i]);
      return modbus_write_bits(ctx, r.address, r.count, bits) == r.count;
    case FunctionCode::kWriteMultipleRegisters:
      return modbus_write_registers(ctx, r.address, r.count, r.values.data()) == r.count;
    default:
      return false;
  }
}

}  // namespace modbus_rtu_driver

int main(int argc, char** argv) {
  double seconds = 2.0;
  std::string csv_path = "benchmark.csv";
  std::string pymodbus_script = PYMODBUS_CLIENT;
  CLI::App app{"The bus layer against plain libmodbus and pymodbus, line use, scale, transports"};
  app.add_option("--seconds", seconds, "time per cell [s]")->check(CLI::Range(0.1, 600.0));
  app.add_option("--csv", csv_path, "CSV file to write");
  app.add_option("--pymodbus", pymodbus_script, "pymodbus client script (bench/pymodbus_client.py)")
      ->check(CLI::ExistingFile);
  bool smoke = false;
  app.add_flag("--smoke", smoke,
               "every table with the least time (scripts/benchmark.sh --smoke): the paced line's "
               "cells for --seconds too, not at least 3 s, and 0.5 s of warm-up per scale run, "
               "not 2 s; the figures then say little");
  CLI11_PARSE(app, argc, argv);
  // A paced line carries ~45-200 transactions/s: a figure needs a few seconds of it.
  const double paced_seconds = smoke ? seconds : std::max(seconds, 3.0);
  const double warm_up_seconds = smoke ? 0.5 : 2.0;
  std::ofstream csv(csv_path);
  csv << "table,case,a,b,ratio\n";
  const std::string dir = "/tmp/modbus_rtu_benchmark_" + std::to_string(getpid());
  const std::vector<Op> ops = {
      {"01 read 8 coils", Request::readCoils(2, 0, 8)},
      {"03 read 3 holding", Request::readHoldingRegisters(2, 0, 3)},
      {"04 read 5 input", Request::readInputRegisters(2, 0, 5)},
      {"05 write coil", Request::writeSingleCoil(2, 1, true)},
      {"15 write 8 coils", Request::writeMultipleCoils(2, 0, std::vector<bool>(8, false))},
      {"16 write 3 holding", Request::writeMultipleRegisters(2, 0, {2500, 2000, 1600})},
  };

  // 1. Software overhead: the simulator answers at once; 115200 baud.
  {
    SimulatorConfig config;
    config.factory.baud = 115200;
    config.devices = {{kYespeedPduType.name, 2}};
    SimulatorOptions options;
    options.link = dir + "/fast";
    Simulator sim(config, options);
    std::string error;
    if (!sim.start(&error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    std::printf("## Software overhead (simulator answering at once, pty, %g s per cell)\n\n",
                seconds);
    const auto py = pymodbusRates(pymodbus_script, options.link, seconds);
    std::printf(
        "| function | plain libmodbus [tx/s] | RtuLink, gap 1 us [tx/s] | ratio | pymodbus "
        "[tx/s] | us/tx RtuLink | us/tx pymodbus | pymodbus / RtuLink | RtuLink, t3.5 gap "
        "[tx/s] |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    for (const Op& op : ops) {
      // Both sides take turns in short rounds and keep their best round, so a moment of load
      // on this shared machine does not fall on one side only.
      LinkConfig lc;
      lc.port = options.link;
      lc.baud = 115200;
      lc.min_gap = 1e-6;
      double plain = 0, ours = 0;
      for (int round = 0; round < 4; ++round) {
        modbus_t* ctx = modbus_new_rtu(options.link.c_str(), 115200, 'N', 8, 1);
        modbus_connect(ctx);
        modbus_set_slave(ctx, 2);
        modbus_set_response_timeout(ctx, 0, 500000);
        plain = std::max(
            plain, transactionRate(seconds / 4, [&] { return plainLibmodbus(ctx, op.request); }));
        modbus_close(ctx);
        modbus_free(ctx);
        RtuLink fast(lc);
        fast.connect(nullptr);
        ours = std::max(
            ours, transactionRate(seconds / 4, [&] { return fast.execute(op.request).ok(); }));
        fast.disconnect();
      }
      lc.min_gap = 0;  // t3.5 = 1.75 ms
      RtuLink spec(lc);
      spec.connect(nullptr);
      const double with_gap =
          transactionRate(seconds, [&] { return spec.execute(op.request).ok(); });
      spec.disconnect();
      const auto found = py.find(std::string(op.name).substr(0, 2));
      const double pym = found == py.end() ? 0.0 : found->second;
      const double us_ours = ours > 0 ? 1e6 / ours : 0.0, us_py = pym > 0 ? 1e6 / pym : 0.0;
      std::printf("| %s | %.0f | %.0f | %.2f | %.0f | %.1f | %.0f | %.1f | %.0f |\n", op.name,
                  plain, ours, ours > 0 ? plain / ours : 0.0, pym, us_ours, us_py,
                  us_ours > 0 ? us_py / us_ours : 0.0, with_gap);
      csv << "overhead," << op.name << "," << plain << "," << ours << ","
          << (ours > 0 ? plain / ours : 0.0) << "\n";
      csv << "pymodbus," << op.name << "," << pym << "," << ours << ","
          << (us_ours > 0 ? us_py / us_ours : 0.0) << "\n";
    }
    std::printf(
        "\nratio = plain libmodbus / RtuLink transactions per second (time per transaction of "
        "RtuLink over libmodbus's), each the best of 4 alternating rounds. pymodbus: Debian's "
        "python3-pymodbus %s, synchronous serial "
        "client (bench/pymodbus_client.py).\n\n",
        py.empty() ? "(did not run)" : "3.0");
  }

  // 2. Line utilisation: the simulator paces the line at its baud.
  std::printf("## Line utilisation (simulator pacing the line, FC03 one register, 8N1)\n\n");
  std::printf("| baud | theoretical [tx/s] | achieved [tx/s] | utilisation |\n|---|---|---|---|\n");
  for (int baud : {9600, 115200}) {
    SimulatorConfig config;
    config.factory.baud = baud;
    config.pace = true;
    config.devices = {{kYespeedPduType.name, 2}};
    SimulatorOptions options;
    options.link = dir + "/paced" + std::to_string(baud);
    Simulator sim(config, options);
    if (!sim.start(nullptr)) return 1;
    LinkConfig lc;
    lc.port = options.link;
    lc.baud = baud;
    RtuLink link(lc);
    link.connect(nullptr);
    const Request r = Request::readHoldingRegisters(2, 0, 1);
    const double ch = characterTime(lc), gap = frameGap(lc);
    // request (8 bytes), t3.5, reply (7 bytes), t3.5 before the next request
    const double theoretical = 1.0 / ((8 + 7) * ch + 2 * gap);
    const double achieved = transactionRate(paced_seconds, [&] { return link.execute(r).ok(); });
    std::printf("| %d | %.1f | %.1f | %.1f %% |\n", baud, theoretical, achieved,
                100.0 * achieved / theoretical);
    csv << "line," << baud << "," << theoretical << "," << achieved << "," << achieved / theoretical
        << "\n";
  }
  std::printf("\n");
  modbus_rtu_driver::benchmarkScale(dir, paced_seconds, warm_up_seconds, csv);
  modbus_rtu_driver::benchmarkTransports(dir, seconds, csv);
  std::printf("CSV: %s\n", csv_path.c_str());
  return 0;
}
