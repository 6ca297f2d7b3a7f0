// The simulator's control commands that act on one device (DEV: "#<index>" in config order, or
// its current address, decimal or 0x hex); the simulator-wide ones and the socket: simulator.cpp
// and sim_control_socket.h.
//   get DEV TABLE ADDR [COUNT]   -> ok V1 V2 ...   (TABLE: coil, discrete_input,
//                         holding_register, input_register)
//   set DEV TABLE ADDR V1 [V2..] -> ok   (coils and holding registers as one
//                         bus write with its checks; discrete inputs and input registers from
//                         outside: optocouplers, telemetry pins; -32768..65535)
//   silence DEV 0|1    the device stops / starts answering (and hearing) anything (0/1 or any
//                      switch word: on/off, true/false, yes/no)
//   fail DEV 0|1       the device answers everything with exception 04
//   corrupt DEV N      the next N replies of the device carry a bad CRC
//   truncate DEV N     the next N replies are cut to half their length
//   wrong_address DEV N  the next N replies name another address (a valid frame)
//   noise DEV N        the next N replies are followed by 5 noise bytes
//   late DEV N MS      the next N replies are sent MS milliseconds late
//   drop DEV PERCENT request|reply   lose that share of the requests (the device does
//                         nothing) or of the replies (the device acts, the reply is lost)
//   stats DEV          -> ok changes N dropped_requests N dropped_replies N   (changes: writes
//                         that changed the device's state or started a PWM run or a flash)
#pragma once

#include <istream>
#include <string>

#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

// The get/set usage line, for the help and the errors.
extern const char* const kSimGetSetUsage;

// A number in [min, max]: decimal, 0x hex or 0 octal (strtol base 0), nothing after it.
bool parseControlNumber(const std::string& text, long min, long max, long* out);

bool isSimDeviceCommand(const std::string& verb);
// Runs `verb` with the rest of its line in `args` on `device`: "ok ..." or "error ...".
// `*stored` is set when what the device stores (the state file) may have changed.
std::string simDeviceCommand(const std::string& verb, SimDevice& device, std::istream& args,
                             SimClock::time_point now, bool* stored);

}  // namespace modbus_rtu_driver
