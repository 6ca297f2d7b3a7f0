// scan: harmless reads over a range of addresses and line settings, naming what answers.
#include <ostream>
#include <set>

#include "modbus_rtu_driver/core/link/make_transport.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"
#include "modbus_rtu_driver/tools/commission_session.h"

namespace modbus_rtu_driver {

namespace {

// An answer, even an exception, means something listens there. Garbage does not: at a wrong
// baud, noise and half frames are what a scan hears most.
bool answered(const Result& r) {
  return r.ok() || r.error == ErrorKind::kException;
}

struct Found {
  int address, baud;
  Parity parity;
  std::string type;
};

// Progress on stderr: redrawn in place on a terminal, a line now and then otherwise (logs).
class Progress {
 public:
  Progress(std::ostream& err, bool terminal, size_t total)
      : err_(err), terminal_(terminal), total_(total) {}
  void at(const std::string& line, int address, size_t found) {
    const size_t percent = total_ ? done_ * 100 / total_ : 100;
    if (terminal_)
      err_ << "\r" << line << ": address " << address << " (" << percent << " %, " << found
           << " found)   " << std::flush;
    else if (line != last_line_ || done_ % 64 == 0)
      err_ << "scanning " << line << " from address " << address << " (" << percent << " %)\n"
           << std::flush;
    last_line_ = line;
    ++done_;
  }
  void clear() {
    if (terminal_) err_ << "\r" << std::string(60, ' ') << "\r" << std::flush;
  }

 private:
  std::ostream& err_;
  bool terminal_;
  size_t total_, done_ = 0;
  std::string last_line_;
};

}  // namespace

Identity identifyDevice(Transport& bus, uint8_t address) {
  Identity id;
  const Result presence = bus.execute(Request::readCoils(address, 0, 1));
  if (presence.error == ErrorKind::kWrongAddress)
    id.note =
        "a reply from another address arrived late: some device answers slower than "
        "--timeout (an LD58A08 with a return delay?)";
  if (!answered(presence)) return id;
  // Probes answered neither with data nor with a refusal: late replies or noise, which leave
  // the type open.
  bool unclear = false;
  auto probe = [&](const Request& request) {
    Result r = bus.execute(request);
    unclear = unclear || !answered(r);
    return r;
  };
  const Result ld = probe(Request::readHoldingRegisters(address, Ld58a08::kAddressRegister, 1));
  if (ld.ok() && ld.values[0] == address) {
    id.present = true;
    id.type = kLd58a08Type.name;
    return id;
  }
  // An LD58A08 answers 0xFF as "whoever you are": it is at its own address, not at 255.
  const bool ld_elsewhere = address == 0xFF && ld.ok();
  id.present = true;
  if (probe(Request::readInputRegisters(address, 0, 5)).ok()) {
    id.type = kYespeedPduType.name;
    return id;
  }
  const Result lc = probe(Request::readHoldingRegisters(address, LcRelay8::kBaudReadRegister, 1));
  if (lc.ok() && lc.values[0] >= 2 && lc.values[0] <= 4) {
    id.type = kLcRelay8Type.name;
  } else if (ld_elsewhere) {
    id.present = false;
    id.note = "address 255: an LD58A08 answered for its address " + std::to_string(ld.values[0]);
  } else {
    id.type = "unknown modbus device";
    if (unclear)
      id.note = "address " + std::to_string(address) +
                ": late or garbled replies; a larger --timeout may tell its type";
  }
  return id;
}

int runScan(const CommissionCommand& cmd, Output& out, const std::atomic<bool>& stop,
            bool err_is_terminal) {
  std::vector<Found> found;
  std::set<std::string> notes;
  Progress progress(out.err(), err_is_terminal,
                    cmd.addresses.size() * cmd.bauds.size() * cmd.parities.size());
  bool done = false;
  for (size_t i = 0; i < cmd.bauds.size() * cmd.parities.size() && !done && !stop; ++i) {
    LinkConfig config = cmd.link;
    config.baud = cmd.bauds[i / cmd.parities.size()];
    config.parity = cmd.parities[i % cmd.parities.size()];
    const std::string line = lineName(config.baud, config.parity);
    const std::unique_ptr<Link> owned = makeTransport(config);
    Link& link = *owned;
    std::string error;
    if (!link.connect(&error)) return out.fail(kExitBusError, error);
    for (const int address : cmd.addresses) {
      if (stop) break;
      progress.at(line, address, found.size());
      const Identity id = identifyDevice(link, static_cast<uint8_t>(address));
      if (!id.note.empty() && notes.insert(id.note).second) out.note(id.note);  // once each
      if (!id.present) continue;
      found.push_back({address, config.baud, config.parity, id.type});
      progress.clear();
      if (!out.json())
        out.event("found " + id.type + " at address " + std::to_string(address) + ", " + line,
                  Json());
      if (cmd.first_only) {
        done = true;
        break;
      }
    }
  }
  progress.clear();
  const bool complete = !stop;
  if (out.json()) {
    std::vector<Json> devices;
    devices.reserve(found.size());
    for (const auto& device : found)
      devices.push_back(Json()
                            .add("address", device.address)
                            .add("baud", device.baud)
                            .add("parity", parityName(device.parity))
                            .add("type", device.type));
    out.event("", Json()
                      .add("ok", !found.empty())
                      .add("exit", found.empty() ? kExitNotFound : kExitOk)
                      .add("complete", complete)
                      .add("devices", devices));
  } else {
    out.event(std::to_string(found.size()) + " device(s) found" +
                  (complete ? "" : " (scan stopped early)"),
              Json());
  }
  if (found.empty())
    out.note(
        "nothing answered; check the wiring and --bauds/--parities, and give a board with a "
        "return delay a --timeout above it");
  return found.empty() ? kExitNotFound : kExitOk;
}

}  // namespace modbus_rtu_driver
