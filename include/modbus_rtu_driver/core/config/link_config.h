// Serial line settings of one bus, with the checks and the timing derived from them.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

enum class Parity { kNone, kEven, kOdd };  // in this order: the LD58A08 stores them as 0-2
enum class DirectionControl { kAuto, kRtsHigh, kRtsLow };  // RTS modes: level while sending
inline constexpr NameTable<DirectionControl, 3> kDirectionControlNames{
    {{DirectionControl::kAuto, "auto"},
     {DirectionControl::kRtsHigh, "rts_high"},
     {DirectionControl::kRtsLow, "rts_low"}}};

struct LinkConfig {
  // A serial device, or another kind of link by its scheme (tcp://HOST:PORT, ...): the kinds
  // register themselves with the links, which parse and check it (core/link/link_types.h).
  std::string port = "/dev/ttyUSB0";
  int baud = 9600;  // 1200-115200
  Parity parity = Parity::kNone;
  int data_bits = 8;  // 7 or 8
  int stop_bits = 1;  // 1 or 2
  // s, wait for the first byte of a reply; 0 = sized per request: its wire time + t3.5 +
  // kTurnaroundAllowance (+ the device's reply delay in every case).
  double response_timeout = 0.0;
  double byte_timeout = 0.0;  // s, silence that ends a reply; 0 = derived from the baud
  int retries = 1;            // extra attempts after a timeout/CRC/wrong-address error
  // s of silence awaited after a failed transaction before the next request, so a reply that
  // comes late is not taken as the answer to that request; 0 = do not wait.
  double late_reply_guard = 0.1;
  double min_gap = 0.0;  // s, silence kept between frames; 0 = t3.5 of the baud
  DirectionControl direction = DirectionControl::kAuto;
  bool low_latency = true;  // ask the USB adapter driver for ASYNC_LOW_LATENCY
  // s added to every timeout of a networked port (tcp://, rtu+tcp://: LinkType::networked) for
  // the network and the gateway.
  double network_allowance = 0.1;
};

// What a device may take to start answering once a request is on the wire, USB adapters' latency
// included: the auto response timeout's allowance.
constexpr double kTurnaroundAllowance = 0.05;

// Empty when valid, else one message naming the field, the value and the allowed range. The
// line settings only: the port is its kind's to check (validateLink, core/link/link_types.h).
std::string validateLinkConfig(const LinkConfig& config);

// Parity's one name in YAML and options; its letter only where a line is written 8N1 and for
// libmodbus. Both from these tables.
inline constexpr NameTable<Parity, 3> kParityNames{
    {{Parity::kNone, "none"}, {Parity::kEven, "even"}, {Parity::kOdd, "odd"}}};
inline constexpr NameTable<Parity, 3> kParityLetters{
    {{Parity::kNone, "N"}, {Parity::kEven, "E"}, {Parity::kOdd, "O"}}};
const char* parityName(Parity parity);  // "none", "even", "odd"
// A parity by its name; otherwise nullopt and `error` lists the names (a letter is refused with
// the name to write: "'E' is not one of none, even, odd (write 'even')").
std::optional<Parity> parseParity(std::string_view text, std::string* error);
char parityLetter(Parity parity);               // 'N', 'E', 'O'
std::string lineName(int baud, Parity parity);  // "9600 8N1"

// The standard rates, slowest first: every check, message and option takes them from here (the
// LD58A08's baud codes 0-7 are these, in order).
inline constexpr int kStandardBauds[] = {1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200};
bool isStandardBaud(int baud);
std::string standardBaudList();  // "1200, 2400, ..., 115200"

// The wire timing every side of a line keeps (the link, the slave role, the simulator), from
// the baud and the bits per character (start + data + parity + stop):
double characterTime(int baud, int bits_per_character);  // s one character takes
// The RTU inter-frame silence: 3.5 characters, fixed at 1.75 ms above 19200 baud (spec).
double frameGap(int baud, int bits_per_character);

// Bits per character on the wire (start + data + parity + stop).
int bitsPerCharacter(const LinkConfig& config);
// Seconds one character takes at the configured baud.
double characterTime(const LinkConfig& config);
double frameGap(const LinkConfig& config);
// Byte timeout used when none is configured: 1.5 characters, at least 0.5 ms... plus slack for
// USB adapters and scheduler jitter.
double effectiveByteTimeout(const LinkConfig& config);
double effectiveMinGap(const LinkConfig& config);
// Seconds to wait for the first byte of the reply to a request of `request_bytes` bytes.
double effectiveResponseTimeout(const LinkConfig& config, size_t request_bytes);
// The same through a gateway, which forwards the reply once it has it whole: the serial
// response timeout, plus the reply's wire time and network_allowance.
double gatewayResponseTimeout(const LinkConfig& config, size_t request_bytes, size_t reply_bytes);
// Silence between the bytes of one reply through a gateway: the byte timeout plus the allowance.
double gatewayByteTimeout(const LinkConfig& config);

}  // namespace modbus_rtu_driver
