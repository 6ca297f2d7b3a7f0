#include "modbus_rtu_driver/sim/simulator.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <termios.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "modbus_rtu_driver/core/link_config.h"
#include "modbus_rtu_driver/sim/sim_lc_relay8.h"

namespace modbus_rtu_driver {

namespace {

double charTime(const SimLineSettings& l) {
  return (l.parity == 'N' ? 10.0 : 11.0) / l.baud;
}

double gapOf(const SimLineSettings& l) {
  return l.baud > 19200 ? 0.00175 : 3.5 * charTime(l);
}

SimClock::duration secs(double s) {
  return std::chrono::duration_cast<SimClock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

bool loadSimulatorConfig(const std::string& path, SimulatorConfig* out, std::string* error) {
  try {
    const YAML::Node root = YAML::LoadFile(path);
    *out = SimulatorConfig{};
    if (root["baud"]) out->factory.baud = root["baud"].as<int>();
    if (!isStandardBaud(out->factory.baud)) {
      *error = "baud: " + std::to_string(out->factory.baud) + " is not a standard rate";
      return false;
    }
    if (root["parity"]) {
      Parity p;
      const std::string text = root["parity"].as<std::string>();
      if (!parseParity(text, &p)) {
        *error = "parity: '" + text + "' is not none, even or odd";
        return false;
      }
      out->factory.parity = p == Parity::kEven ? 'E' : p == Parity::kOdd ? 'O' : 'N';
    }
    if (root["pace"]) out->pace = root["pace"].as<bool>();
    if (!root["devices"] || !root["devices"].IsSequence()) {
      *error = "devices: missing (a list of {type, address})";
      return false;
    }
    int i = 0;
    for (const auto& d : root["devices"]) {
      const std::string where = "devices[" + std::to_string(i++) + "]";
      SimulatorConfig::Entry e{d["type"].as<std::string>(""), d["address"].as<int>(-1)};
      if (!makeSimDevice(e.type, 1, out->factory)) {
        *error = where + "/type: '" + e.type + "' is not ld58a08, lc_relay8 or yespeed_pdu";
        return false;
      }
      if (e.address < 1 || e.address > 255) {
        *error = where + "/address: " + std::to_string(e.address) + " is outside 1-255";
        return false;
      }
      out->devices.push_back(e);
    }
    return true;
  } catch (const YAML::Exception& e) {
    *error = path + ": " + e.what();
    return false;
  }
}

Simulator::Simulator(SimulatorConfig config, SimulatorOptions options)
    : config_(std::move(config)), options_(std::move(options)) {
  if (options_.control.empty()) options_.control = options_.link + ".ctl";
  for (const auto& e : config_.devices)
    devices_.push_back(makeSimDevice(e.type, static_cast<uint8_t>(e.address), config_.factory));
}

Simulator::~Simulator() {
  stop();
}

bool Simulator::start(std::string* error) {
  auto fail = [&](const std::string& what) {
    if (error) *error = what + ": " + std::strerror(errno);
    stop();
    return false;
  };
  loadState();
  if (!pty_.open(options_.link, config_.factory.baud, error)) {
    stop();
    return false;
  }
  listen_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", options_.control.c_str());
  unlink(options_.control.c_str());
  if (listen_fd_ < 0 || bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      listen(listen_fd_, 8) != 0)
    return fail("cannot listen on " + options_.control);
  running_ = true;
  thread_ = std::thread(&Simulator::run, this);
  return true;
}

void Simulator::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  for (int fd : clients_) close(fd);
  clients_.clear();
  client_buffers_.clear();
  if (listen_fd_ >= 0) close(listen_fd_);
  listen_fd_ = -1;
  pty_.close();
  if (!options_.control.empty()) unlink(options_.control.c_str());
}

SimLineSettings Simulator::lineSettings() const {
  return pty_.lineSettings();
}

void Simulator::run() {
  while (running_) {
    std::vector<pollfd> fds{{pty_.fd(), POLLIN, 0}, {listen_fd_, POLLIN, 0}};
    for (int c : clients_) fds.push_back({c, POLLIN, 0});
    poll(fds.data(), fds.size(), 2);
    std::lock_guard<std::mutex> lock(mutex_);
    const auto now = SimClock::now();
    if (power_cycle_requested_.exchange(false)) powerCycle();
    for (auto& d : devices_) d->tick(now);
    bool got = false;
    if (fds[0].revents & POLLIN) {
      uint8_t buf[512];
      const ssize_t n = read(pty_.fd(), buf, sizeof buf);
      if (n > 0) {
        framer_.push(buf, static_cast<size_t>(n));
        last_byte_ = now;
        got = true;
      }
    }
    const double gap = std::max(gapOf(lineSettings()), 0.004);  // ptys deliver in bursts
    const bool silence = !got && framer_.pending() && now - last_byte_ > secs(gap);
    for (const Bytes& frame : framer_.take(silence)) processFrame(frame);
    bad_crc_ = framer_.dropped();
    serveControl();
  }
}

void Simulator::processFrame(const Bytes& frame) {
  ++frames_;
  if (options_.verbose) std::printf("rx %s\n", toHex(frame).c_str());
  const uint8_t slave = frame[0];
  const auto request = decodeRequest(frame);
  const SimLineSettings line = lineSettings();
  const auto now = SimClock::now();
  bool wrote = false;
  for (auto& d : devices_) {
    if (d->silenced || d->line().baud != line.baud || d->line().parity != line.parity) continue;
    std::optional<Bytes> reply;
    const double delay = d->replyDelay();  // a new return delay applies from the next request
    if (slave == kBroadcastAddress) {
      if (!request) continue;
      if (auto* lc = dynamic_cast<SimLcRelay8*>(d.get())) reply = lc->handleAtZero(*request);
      if (!reply) d->handle(*request, now);  // broadcast: applied, not answered
      wrote = wrote || !isReadFunction(request->function);
      if (reply) {
        answer(*d, frame, *reply, delay);
        wrote = true;
        break;
      }
      continue;
    }
    if (!d->answersTo(slave, request ? &*request : nullptr)) continue;
    if (!request) {
      answer(*d, frame, d->unknownFunction(slave, frame[1]), delay);
    } else if (d->failing) {
      answer(*d, frame, encodeException(slave, frame[1], kSlaveDeviceFailure), delay);
    } else {
      reply = d->handle(*request, now);
      wrote = !isReadFunction(request->function);
      if (reply) answer(*d, frame, *reply, delay);
    }
    break;  // one device answers an address
  }
  if (wrote) saveState();
}

void Simulator::answer(SimDevice& device, const Bytes& request, const Bytes& sent, double delay) {
  Bytes reply = sent;
  if (device.corrupt_replies > 0) {
    --device.corrupt_replies;
    reply.back() ^= 0xA5;
  }
  const SimLineSettings line = device.line();
  auto ready = SimClock::now() + secs(delay);
  if (config_.pace) {
    // The request took its wire time to arrive, then the line rests t3.5 before the reply.
    ready = std::max(ready, busy_until_) + secs(request.size() * charTime(line) + gapOf(line));
  }
  std::this_thread::sleep_until(ready);
  if (options_.verbose) std::printf("tx %s\n", toHex(reply).c_str());
  size_t off = 0;
  while (off < reply.size()) {
    const ssize_t n = write(pty_.fd(), reply.data() + off, reply.size() - off);
    if (n <= 0) break;
    off += static_cast<size_t>(n);
  }
  ++answered_;
  if (config_.pace) {
    busy_until_ = SimClock::now() + secs(reply.size() * charTime(line) + gapOf(line));
    std::this_thread::sleep_until(busy_until_);  // the reply occupies the line
  }
}

SimDevice* Simulator::find(const std::string& name) {
  if (!name.empty() && name[0] == '#') {
    const size_t i = std::strtoul(name.c_str() + 1, nullptr, 10);
    return i < devices_.size() ? devices_[i].get() : nullptr;
  }
  const int address = std::atoi(name.c_str());
  for (auto& d : devices_)
    if (d->address() == address) return d.get();
  return nullptr;
}

void Simulator::powerCycle() {
  for (auto& d : devices_) d->powerCycle();
  saveState();
}

void Simulator::saveState() {
  if (options_.state_file.empty()) return;
  YAML::Node root;
  for (auto& d : devices_) {
    YAML::Node n;
    n["type"] = d->type();
    d->saveState(n);
    root["devices"].push_back(n);
  }
  std::ofstream(options_.state_file + ".tmp") << root << "\n";
  std::rename((options_.state_file + ".tmp").c_str(), options_.state_file.c_str());
}

void Simulator::loadState() {
  if (options_.state_file.empty() || access(options_.state_file.c_str(), R_OK) != 0) return;
  try {
    const YAML::Node root = YAML::LoadFile(options_.state_file);
    for (size_t i = 0; i < devices_.size() && i < root["devices"].size(); ++i)
      if (root["devices"][i]["type"].as<std::string>("") == devices_[i]->type())
        devices_[i]->loadState(root["devices"][i]);
  } catch (const YAML::Exception& e) {
    std::fprintf(stderr, "ignoring state file %s: %s\n", options_.state_file.c_str(), e.what());
  }
}

std::string Simulator::command(const std::string& line) {
  std::lock_guard<std::mutex> lock(mutex_);
  return doCommand(line);
}

std::string Simulator::doCommand(const std::string& line) {
  std::istringstream in(line);
  std::string verb, name, table_name;
  in >> verb;
  const auto now = SimClock::now();
  if (verb == "power_cycle") {
    powerCycle();
    return "ok";
  }
  if (verb == "frames")
    return "ok " + std::to_string(frames_) + " " + std::to_string(answered_) + " " +
           std::to_string(bad_crc_);
  if (verb == "info") {
    std::string out = "ok";
    for (size_t i = 0; i < devices_.size(); ++i) {
      const auto& d = devices_[i];
      out += " #" + std::to_string(i) + ":" + d->type() + ":" + std::to_string(d->address()) + ":" +
             std::to_string(d->line().baud) + ":" + d->line().parity;
    }
    return out;
  }
  in >> name;
  SimDevice* d = find(name);
  if (!d) return "error no device '" + name + "'";
  if (verb == "silence" || verb == "fail" || verb == "corrupt") {
    int n = 1;
    in >> n;
    if (verb == "silence") d->silenced = n != 0;
    if (verb == "fail") d->failing = n != 0;
    if (verb == "corrupt") d->corrupt_replies = n;
    return "ok";
  }
  Table table;
  uint32_t address = 0;
  if (!(in >> table_name) || !parseTable(table_name, &table) || !(in >> address) ||
      address > 0xFFFF)
    return "error usage: get|set DEVICE coil|input|holding|ireg ADDRESS [COUNT|VALUES]";
  if (verb == "get") {
    uint32_t count = 1;
    in >> count;
    std::string out = "ok";
    for (uint32_t a = address; a < address + count; ++a) {
      uint16_t v = 0;
      const uint8_t e = d->read(table, static_cast<uint16_t>(a), now, &v);
      if (e) return "error " + exceptionName(e) + " at " + std::to_string(a);
      out += " " + std::to_string(v);
    }
    return out;
  }
  if (verb == "set") {
    uint32_t v = 0;
    for (uint32_t a = address; in >> v; ++a) {
      const uint8_t e =
          d->setDirect(table, static_cast<uint16_t>(a), static_cast<uint16_t>(v), now);
      if (e) return "error " + exceptionName(e) + " at " + std::to_string(a);
    }
    saveState();
    return "ok";
  }
  return "error unknown command '" + verb + "'";
}

void Simulator::serveControl() {
  const int c = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK);
  if (c >= 0) {
    clients_.push_back(c);
    client_buffers_.emplace_back();
  }
  for (size_t i = 0; i < clients_.size();) {
    char buf[512];
    const ssize_t n = read(clients_[i], buf, sizeof buf);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK)) {
      close(clients_[i]);
      clients_.erase(clients_.begin() + static_cast<long>(i));
      client_buffers_.erase(client_buffers_.begin() + static_cast<long>(i));
      continue;
    }
    if (n > 0) client_buffers_[i].append(buf, static_cast<size_t>(n));
    size_t nl;
    while ((nl = client_buffers_[i].find('\n')) != std::string::npos) {
      const std::string reply = doCommand(client_buffers_[i].substr(0, nl)) + "\n";
      client_buffers_[i].erase(0, nl + 1);
      if (write(clients_[i], reply.data(), reply.size()) < 0) break;
    }
    ++i;
  }
}

}  // namespace modbus_rtu_driver
