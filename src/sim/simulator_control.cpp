// The simulator's control interface: a Unix stream socket, one text command per line, one reply
// line each ("ok ..." or "error <message>"). Devices are named "#<index>" (config order) or by
// their current address (decimal or 0x hex).
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
//   power_cycle [DEV]  every device (or only DEV) off and on (pending settings apply, outputs
//                         off)
//   info               -> ok #0:TYPE:ADDRESS:BAUD:PARITY #1:...   (one item per device)
//   frames             -> ok RECEIVED ANSWERED DROPPED   (valid frames in, replies out, runs of
//                         bytes dropped: bad CRC or noise)
//   gateway            -> ok port P connections N accepted N dropped N   (RTU over TCP)
//   gateway_drop [MS]  the gateway closes its connections; with MS it refuses new ones for MS
//                         ms (a gateway reboot)
//   help               -> ok <the command list>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "modbus_rtu_driver/core/modbus/switch_words.h"
#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

namespace {

constexpr size_t kMaxLine = 4096;
const char* kUsage =
    "usage: get|set DEVICE coil|discrete_input|holding_register|input_register ADDRESS [COUNT | "
    "VALUES...]";

bool parseNumber(const std::string& text, long min, long max, long* out) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 0);
  if (errno || *end || v < min || v > max) return false;
  *out = v;
  return true;
}

}  // namespace

bool Simulator::openControl(std::string* error) {
  sockaddr_un addr{};
  if (options_.control.size() >= sizeof addr.sun_path) {
    if (error) *error = "control socket path too long: " + options_.control;
    return false;
  }
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", options_.control.c_str());
  // A socket there that accepts a connection is a running simulator's (given the same --control
  // with another --link): refused, never taken over. One that refuses is stale: replaced.
  const int probe = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const bool answers =
      probe >= 0 && connect(probe, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  if (probe >= 0) close(probe);
  if (answers) {
    if (error)
      *error = "control socket " + options_.control +
               " belongs to a running simulator (it accepts connections): give each simulator "
               "its own --control";
    return false;
  }
  listen_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  unlink(options_.control.c_str());  // a stale socket of an earlier run
  if (listen_fd_ < 0 || bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      listen(listen_fd_, 16) != 0) {
    if (error) *error = "cannot listen on " + options_.control + ": " + std::strerror(errno);
    return false;
  }
  struct stat st {};
  if (stat(options_.control.c_str(), &st) == 0) control_inode_ = {st.st_dev, st.st_ino};
  return true;
}

void Simulator::closeControl() {
  if (listen_fd_ < 0) return;
  close(listen_fd_);
  listen_fd_ = -1;
  // Only the socket this run made: never one that replaced it since (see openControl).
  struct stat st {};
  if (control_inode_.second != 0 && stat(options_.control.c_str(), &st) == 0 &&
      std::make_pair(st.st_dev, st.st_ino) == control_inode_)
    unlink(options_.control.c_str());
  control_inode_ = {};
}

void Simulator::serveControl() {
  for (int c; (c = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC)) >= 0;)
    clients_.push_back({c, {}});
  for (size_t i = 0; i < clients_.size();) {
    Client& client = clients_[i];
    char buf[512];
    const ssize_t n = read(client.fd, buf, sizeof buf);
    bool drop = n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
    if (n > 0) client.input.append(buf, static_cast<size_t>(n));
    for (size_t nl; !drop && (nl = client.input.find('\n')) != std::string::npos;) {
      const std::string reply = doCommand(client.input.substr(0, nl)) + "\n";
      client.input.erase(0, nl + 1);
      drop = ::send(client.fd, reply.data(), reply.size(), MSG_NOSIGNAL) !=
             static_cast<ssize_t>(reply.size());
    }
    if (!drop && client.input.size() > kMaxLine) drop = true;  // no line end in sight
    if (drop) {
      close(client.fd);
      clients_.erase(clients_.begin() + static_cast<long>(i));
    } else {
      ++i;
    }
  }
}

std::string Simulator::command(const std::string& line) {
  std::lock_guard<std::mutex> lock(mutex_);
  return doCommand(line);
}

SimDevice* Simulator::find(const std::string& name) {
  long v = 0;
  if (name.size() > 1 && name[0] == '#') {
    if (!parseNumber(name.substr(1), 0, static_cast<long>(devices_.size()) - 1, &v)) return nullptr;
    return devices_[static_cast<size_t>(v)].get();
  }
  if (!parseNumber(name, 0, 255, &v)) return nullptr;
  for (auto& d : devices_)
    if (d->address() == v) return d.get();
  return nullptr;
}

std::string Simulator::doCommand(const std::string& line) {
  std::istringstream in(line);
  std::string verb, name;
  in >> verb;
  if (verb == "power_cycle") {
    if (!(in >> name)) {
      powerCycle(SimClock::now());
      return "ok";
    }
    SimDevice* d = find(name);  // one board's own supply: the others and the line run on
    if (!d) return "error no device '" + name + "' (#index or address; see info)";
    d->powerCycle(SimClock::now());
    saveState();
    return "ok";
  }
  if (verb == "gateway" || verb == "gateway_drop") {
    if (!gateway_.enabled()) return "error no RTU-over-TCP gateway (start with --rtu-tcp PORT)";
    if (verb == "gateway") return "ok " + gateway_.status();
    std::string ms_text;
    long ms = 0;
    if (in >> ms_text && !parseNumber(ms_text, 0, 600000, &ms))
      return "error gateway_drop: MS '" + ms_text + "' is not 0-600000";
    gateway_.drop(static_cast<double>(ms) / 1000.0, SimClock::now());
    return "ok";
  }
  if (verb == "frames")
    return "ok " + std::to_string(frames_) + " " + std::to_string(answered_) + " " +
           std::to_string(framer_.dropped());
  if (verb == "info") {
    std::string out = "ok";
    for (size_t i = 0; i < devices_.size(); ++i) {
      const SimDevice& d = *devices_[i];
      out += " #" + std::to_string(i) + ":" + d.type() + ":" + std::to_string(d.address()) + ":" +
             std::to_string(d.line().baud) + ":" + parityLetter(d.line().parity);
    }
    return out;
  }
  if (verb == "help")
    return "ok get set silence fail corrupt truncate wrong_address noise late drop stats "
           "power_cycle [DEV] info frames gateway gateway_drop help; " +
           std::string(kUsage);
  static const char* kDeviceVerbs[] = {"get",     "set",      "silence",       "fail",
                                       "corrupt", "truncate", "wrong_address", "noise",
                                       "late",    "drop",     "stats"};
  if (std::find(std::begin(kDeviceVerbs), std::end(kDeviceVerbs), verb) == std::end(kDeviceVerbs))
    return "error unknown command '" + verb + "' (try help)";
  in >> name;
  SimDevice* d = find(name);
  if (!d) return "error no device '" + name + "' (#index or address; see info)";
  return deviceCommand(verb, *d, in);
}

std::string Simulator::deviceCommand(const std::string& verb, SimDevice& d, std::istream& in) {
  const auto now = SimClock::now();
  std::string a, b;
  long n = 0, address = 0;
  if (verb == "stats")
    return "ok changes " + std::to_string(d.changes) + " dropped_requests " +
           std::to_string(d.dropped_requests) + " dropped_replies " +
           std::to_string(d.dropped_replies);
  if (verb == "silence" || verb == "fail") {
    in >> a;
    if (a.empty()) a = "1";
    const auto on = parseSwitch(a);
    if (!on) return "error " + verb + ": '" + a + "' is not one of " + std::string(kSwitchWords);
    (verb == "silence" ? d.silenced : d.failing) = *on;
    return "ok";
  }
  if (verb == "drop") {
    in >> a >> b;
    if (!parseNumber(a, 0, 100, &n)) return "error drop: '" + a + "' is not a percentage 0-100";
    if (b != "request" && b != "reply") return "error drop: say request or reply, not '" + b + "'";
    (b == "request" ? d.drop_request_percent : d.drop_reply_percent) = static_cast<int>(n);
    return "ok";
  }
  if (verb == "corrupt" || verb == "truncate" || verb == "wrong_address" || verb == "noise" ||
      verb == "late") {
    in >> a;
    if (!parseNumber(a, 0, 1000000, &n)) return "error " + verb + ": '" + a + "' is not a count";
    if (verb == "late") {
      in >> b;
      if (!parseNumber(b, 0, 60000, &address))
        return "error late: '" + b + "' is not 0-60000 milliseconds";
      d.late_ms = static_cast<int>(address);
    }
    int& counter = verb == "corrupt"    ? d.corrupt_replies
                   : verb == "truncate" ? d.truncate_replies
                   : verb == "noise"    ? d.noise_replies
                   : verb == "late"     ? d.late_replies
                                        : d.wrong_address_replies;
    counter = static_cast<int>(n);
    return "ok";
  }
  if (!(in >> a)) return std::string("error no table; ") + kUsage;
  std::string table_error;
  const auto parsed_table = parseTableName(a, &table_error);
  if (!parsed_table) return "error table " + table_error + "; " + kUsage;
  const Table table = *parsed_table;
  if (!(in >> b) || !parseNumber(b, 0, 0xFFFF, &address))
    return "error address '" + b + "' is not 0-65535; " + std::string(kUsage);
  if (verb == "get") {
    long count = 1;
    if (in >> b && !parseNumber(b, 1, 2000, &count)) return "error count '" + b + "' is not 1-2000";
    std::string out = "ok";
    for (long i = address; i < address + count; ++i) {
      uint16_t v = 0;
      const uint8_t e = i > 0xFFFF ? static_cast<uint8_t>(kIllegalDataAddress)
                                   : d.read(table, static_cast<uint16_t>(i), now, &v);
      if (e) return "error " + exceptionName(e) + " at " + std::to_string(i);
      out += " " + std::to_string(v);
    }
    return out;
  }
  std::vector<uint16_t> values;
  while (in >> b) {
    long v = 0;
    if (!parseNumber(b, -32768, 65535, &v)) return "error value '" + b + "' is not 16 bits";
    values.push_back(static_cast<uint16_t>(v));  // negative: two's complement (temperature)
  }
  if (values.empty()) return "error set needs at least one value; " + std::string(kUsage);
  if (address + static_cast<long>(values.size()) > 0x10000)
    return "error " + exceptionName(kIllegalDataAddress) + " at 65536";
  if (table == Table::kCoil || table == Table::kHoldingRegister) {  // one write, checked as a whole
    for (uint16_t v : values)
      if (table == Table::kCoil && v > 1) return "error coil values are 0 or 1";
    const uint8_t e = d.write(table, static_cast<uint16_t>(address), values, now);
    if (e) return "error " + exceptionName(e) + " at " + std::to_string(address);
    saveState();
    return "ok";
  }
  for (size_t i = 0; i < values.size(); ++i) {
    const long at = address + static_cast<long>(i);
    const uint8_t e = d.setDirect(table, static_cast<uint16_t>(at), values[i], now);
    if (e) return "error " + exceptionName(e) + " at " + std::to_string(at);
  }
  saveState();
  return "ok";
}

}  // namespace modbus_rtu_driver
