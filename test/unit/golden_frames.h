// Loads test/data/golden_frames.tsv: every literal frame the device manuals print.
#pragma once

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

struct GoldenFrame {
  std::string seed, device;
  int slave = 0;
  Bytes request, response;  // response empty when the manual shows none
  std::string meaning;
  bool request_crc_printed_wrong = false;
};

inline std::vector<GoldenFrame> loadGoldenFrames(const std::string& path) {
  std::vector<GoldenFrame> rows;
  std::ifstream in(path);
  // A missing file must fail the tests that loop over the rows, not let them pass on none.
  if (!in) throw std::runtime_error("cannot read the golden frames at " + path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("seed\t", 0) == 0) continue;
    std::vector<std::string> cols;
    std::stringstream ss(line);
    std::string col;
    while (std::getline(ss, col, '\t')) cols.push_back(col);
    if (cols.size() < 6) continue;
    GoldenFrame g;
    g.seed = cols[0];
    g.device = cols[1];
    g.slave = std::stoi(cols[2]);
    g.request = fromHex(cols[3]).value_or(Bytes{});
    if (cols[4] != "-") g.response = fromHex(cols[4]).value_or(Bytes{});
    g.meaning = cols[5];
    g.request_crc_printed_wrong = g.meaning.find("wrong CRC") != std::string::npos;
    rows.push_back(g);
  }
  if (rows.empty()) throw std::runtime_error("no golden frames in " + path);
  return rows;
}

}  // namespace modbus_rtu_driver
