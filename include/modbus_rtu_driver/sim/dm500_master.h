// Plays the DM500 controller: a Modbus RTU master on a pty, sending what its G-code macros send
// (FC15 / FC16 writes of macro buffer bytes, FC01-04 reads), checking the replies, and running
// a scripted sequence. Script, one step per line ('#' comments):
//   write_coils ID ADDR COUNT BYTE...     FC15, coils packed in macro bytes (hex), as #1204/#1230
//   write_bytes ID ADDR BYTE...           FC16, macro bytes (decimal) two per register, low first
//   write_coil ID ADDR 0|1                FC05        write_register ID ADDR VALUE   FC06
//   read_TABLE ID ADDR COUNT [expect V...]  TABLE: coil, discrete_input, holding_register,
//                                           input_register (read_holding_register 1 5 2)
//   wait_TABLE ID ADDR COUNT equals V... within SECONDS
//   wait_ready ID within SECONDS          until slave ID answers (the node opened the port)
//   raw HEX...                            send bytes as they are
//   garbage ID ROUNDS SEED ADDR VALUE     ROUNDS of random junk (noise, frames with bad CRCs,
//                                         unknown functions, odd reads, frames for other ids),
//                                         each followed by a read of holding ADDR that must
//                                         answer VALUE
//   sleep SECONDS
// Any request step may end with `exception CODE` or `silence` instead of a normal answer.
#pragma once

#include <string>

#include "modbus_rtu_driver/core/modbus/frame.h"
#include "modbus_rtu_driver/sim/pty_link.h"

namespace modbus_rtu_driver {

class Dm500Master {
 public:
  Dm500Master(PtyLink& pty, double timeout) : pty_(pty), timeout_(timeout) {}
  // Runs one script line. False with `why` when the step failed.
  bool step(const std::string& line, std::string* why);
  // One transaction: send, read the reply (or time out).
  Result transact(const Request& request);

 private:
  bool garbage(uint8_t id, long rounds, unsigned seed, uint16_t address, uint16_t value,
               std::string* why);
  Bytes readFor(double seconds, size_t max_bytes, const Request* request);

  PtyLink& pty_;
  double timeout_;
};

}  // namespace modbus_rtu_driver
