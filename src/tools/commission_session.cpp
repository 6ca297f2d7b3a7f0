// Running a parsed modbus_rtu_commission command: open the port, hand over to the command group.
#include "modbus_rtu_driver/tools/commission_session.h"

#include <istream>
#include <memory>
#include <ostream>

#include "modbus_rtu_driver/core/link/make_link.h"

namespace modbus_rtu_driver {

bool Session::confirm(const std::string& question) {
  if (cmd.yes) return true;
  out.err() << question << " [y/N] " << std::flush;
  std::string answer;
  if (!std::getline(in, answer)) {
    out.err() << "\n";
    return false;
  }
  return answer == "y" || answer == "Y" || answer == "yes";
}

int runCommission(const CommissionCommand& cmd, const CommissionIo& io) {
  Output out(cmd.json, io.out, io.err);
  if (cmd.command == "scan") return runScan(cmd, out, io.stop, io.err_is_terminal);
  const std::unique_ptr<Link> link = makeLink(cmd.link, cmd.target);
  std::string error;
  if (!link->connect(&error)) return out.fail(kExitBusError, error);
  Session session{cmd, *link, out, io.in, io.stop};
  const bool table = cmd.command == "read" || cmd.command == "write" || cmd.command == "watch";
  return table ? runTableCommand(session) : runDeviceCommand(session);
}

}  // namespace modbus_rtu_driver
