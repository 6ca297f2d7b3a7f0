// scan: harmless reads over a range of addresses and line settings, naming what answers.
#include <ostream>
#include <set>

#include "modbus_rtu_driver/core/link/make_link.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/tools/commission_session.h"

namespace modbus_rtu_driver {

namespace {

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

// The coil read first: most boards answer it, and a silent address costs one read only. Then
// each registered type's probe, in probe order (devices/commissioning.h).
Identity identifyDevice(Transport& transport, uint8_t address) {
  Identity id;
  const Result presence = transport.execute(Request::readCoils(address, 0, 1));
  if (presence.error == ErrorKind::kWrongAddress)
    id.note =
        "a reply from another address arrived late: some device answers slower than "
        "--timeout (a board with a return delay?)";
  if (!answered(presence)) return id;
  // Probes answered neither with data nor with a refusal: late replies or noise, which leave
  // the type open.
  bool unclear = false;
  std::string elsewhere;  // a board that answered for another address of its own
  for (const CommissioningType& t : commissioningTypes()) {
    const Probe p = t.commissioning->probe(transport, address);
    unclear = unclear || p.unclear;
    if (p.kind == Probe::kYes) {
      id.present = true;
      id.type = t.type->name;
      return id;
    }
    if (p.kind == Probe::kElsewhere && elsewhere.empty()) elsewhere = p.note;
  }
  if (!elsewhere.empty()) {
    id.note = "address " + std::to_string(address) + ": " + elsewhere;
    return id;
  }
  id.present = true;
  id.type = "unknown modbus device";
  if (unclear)
    id.note = "address " + std::to_string(address) +
              ": late or garbled replies; a larger --timeout may tell its type";
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
    const std::unique_ptr<Link> owned = makeLink(config, cmd.target);
    Link& link = *owned;
    std::string error;
    if (!link.connect(&error)) return out.fail(kExitBusError, error);
    for (const int address : cmd.addresses) {
      if (stop) break;
      progress.at(line, address, found.size());
      const uint64_t stale_before = link.stats().stale_bytes;
      const Identity id = identifyDevice(link, static_cast<uint8_t>(address));
      if (!id.note.empty() && notes.insert(id.note).second) out.note(id.note);  // once each
      // Through a gateway that answers for silence (tcp://) a stale answer is the gateway's to a
      // request given up (dropped by its transaction id): the gateway still works through
      // those, and each address waits behind them, so a device there may be missed.
      if (link.target().type->answers_for_silence && link.stats().stale_bytes > stale_before) {
        const std::string note =
            "the gateway answered earlier requests after --timeout (its own response timeout "
            "is longer): scan with a --timeout above it, or devices may be missed";
        if (notes.insert(note).second) out.note(note);
      }
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
  if (found.empty()) {
    // Where each type's boards are when new (their descriptors' factory settings).
    std::vector<std::string> boards;
    for (const CommissioningType& t : commissioningTypes()) {
      const FactorySettings& f = t.type->factory;
      if (!f.address || !f.baud) continue;
      boards.push_back(std::string(t.type->name) + " at " + std::to_string(f.address) + " " +
                       lineName(f.baud, f.parity));
    }
    const std::string factory = join(boards);
    out.note(
        "nothing answered; check the wiring and --bauds/--parities, and give a board with a "
        "return delay a --timeout above it" +
        (factory.empty() ? std::string() : " (factory settings: " + factory + ")"));
  }
  return found.empty() ? kExitNotFound : kExitOk;
}

}  // namespace modbus_rtu_driver
