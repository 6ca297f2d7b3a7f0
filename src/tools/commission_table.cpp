// read / write / watch of any Modbus table at any address.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/tools/commission_session.h"

namespace modbus_rtu_driver {

namespace {

using Steady = std::chrono::steady_clock;

class TableCommands {
 public:
  explicit TableCommands(Session& s) : s_(s), c_(s.cmd), slave_(static_cast<uint8_t>(c_.address)) {}

  int run() {
    if (c_.command == "read") return read();
    if (c_.command == "write") return write();
    return watch();
  }

 private:
  bool bits() const { return isBitTable(c_.table); }

  // "holding_register 253 (0x00FD)"
  std::string item(int offset) const {
    const int a = c_.start + offset;
    char hex[16];
    std::snprintf(hex, sizeof hex, " (0x%04X)", a);
    return tableName(c_.table) + (" " + std::to_string(a)) + (bits() ? "" : hex);
  }

  Json fields() const {
    return Json()
        .add("address", c_.address)
        .add("table", std::string(tableName(c_.table)))
        .add("start", c_.start);
  }

  Request readRequest() const {
    const auto start = static_cast<uint16_t>(c_.start);
    const auto n = static_cast<uint16_t>(c_.count);
    return Request::read(slave_, c_.table, start, n);
  }

  int read() {
    const Result r = s_.transport.execute(readRequest());
    if (!r.ok()) return s_.out.fail(r);
    std::vector<std::string> lines;
    lines.reserve(r.values.size());
    for (size_t i = 0; i < r.values.size(); ++i)
      lines.push_back(item(static_cast<int>(i)) + ": " + std::to_string(r.values[i]));
    s_.out.result(join(lines, "\n"), fields().add("values", r.values));
    return kExitOk;
  }

  int write() {
    const auto start = static_cast<uint16_t>(c_.start);
    const bool one = c_.values.size() == 1 && !c_.multiple;
    Request req;
    if (c_.table == Table::kCoil)
      req = one ? Request::writeSingleCoil(slave_, start, c_.values[0] != 0)
                : Request::writeMultipleCoils(
                      slave_, start, std::vector<bool>(c_.values.begin(), c_.values.end()));
    else
      req = one ? Request::writeSingleRegister(slave_, start, c_.values[0])
                : Request::writeMultipleRegisters(slave_, start, c_.values);
    const Result r = s_.transport.execute(req);
    if (!r.ok()) return s_.out.fail(r);
    const int fc = static_cast<int>(req.function);
    const std::string span = tableName(c_.table) + (" " + std::to_string(c_.start)) +
                             (c_.count > 1 ? "-" + std::to_string(c_.start + c_.count - 1) : "");
    s_.out.result(
        "wrote " + span + " with function " + std::to_string(fc) + "; the device confirmed",
        fields().add("count", c_.count).add("function", fc));
    return kExitOk;
  }

  // Sleeps `seconds` unless stopped first.
  void pause(double seconds) {
    const auto until = Steady::now() + std::chrono::duration_cast<Steady::duration>(
                                           std::chrono::duration<double>(seconds));
    while (!s_.stop && Steady::now() < until)
      std::this_thread::sleep_for(
          std::min<Steady::duration>(until - Steady::now(), std::chrono::milliseconds(20)));
  }

  // Prints the values when they differ from `last` (all of them the first time).
  void report(double t, const std::vector<uint16_t>& values, const std::vector<uint16_t>& last) {
    std::vector<std::string> human;
    std::vector<uint16_t> changed;
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "+%.2f s  ", t);
    for (size_t i = 0; i < values.size(); ++i) {
      if (!last.empty() && values[i] == last[i]) continue;
      human.push_back(item(static_cast<int>(i)) + ": " +
                      (last.empty() ? "" : std::to_string(last[i]) + " -> ") +
                      std::to_string(values[i]));
      changed.push_back(static_cast<uint16_t>(c_.start + i));
    }
    s_.out.event(stamp + join(human),
                 fields().add("t", t).add("values", values).add("changed", changed));
  }

  int watch() {
    const auto t0 = Steady::now();
    std::vector<uint16_t> last;
    int exit_code = kExitNotFound;
    bool failing = false;
    for (int n = 0; !s_.stop && (c_.polls == 0 || n < c_.polls); ++n) {
      if (n) pause(c_.interval);
      if (s_.stop) break;
      const Result r = s_.transport.execute(readRequest());
      const double t = std::chrono::duration<double>(Steady::now() - t0).count();
      if (!r.ok()) {
        if (!failing) s_.out.note("read failed: " + r.message);  // once, not every poll
        failing = true;
        if (last.empty()) exit_code = exitCodeFor(r);
        continue;
      }
      if (failing) s_.out.note("answering again");
      failing = false;
      exit_code = kExitOk;
      if (r.values != last) report(t, r.values, last);
      last = r.values;
    }
    return exit_code;
  }

  Session& s_;
  const CommissionCommand& c_;
  uint8_t slave_;
};

}  // namespace

int runTableCommand(Session& session) {
  return TableCommands(session).run();
}

}  // namespace modbus_rtu_driver
