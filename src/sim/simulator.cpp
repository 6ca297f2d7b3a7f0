// The line of the simulator: the thread, framing, dispatch to the devices and replies; the
// state file (what the devices store); the control commands. Its configuration file and the
// registry of the simulated types: simulator_config.cpp; the control socket:
// sim_control_socket.cpp; the commands on one device (get, set, the faults, stats):
// sim_device_commands.cpp. The simulator-wide commands:
//   power_cycle [DEV]  every device (or only DEV) off and on (pending settings apply, outputs
//                         off)
//   info               -> ok #0:TYPE:ADDRESS:BAUD:PARITY #1:...   (one item per device)
//   frames             -> ok RECEIVED ANSWERED DROPPED   (valid frames in, replies out, runs of
//                         bytes dropped: bad CRC or noise)
//   gateway            -> ok port P connections N accepted N dropped N   (RTU over TCP)
//   gateway_drop [MS]  the gateway closes its connections; with MS it refuses new ones for MS
//                         ms (a gateway reboot)
//   help               -> ok <the command list>
#include "modbus_rtu_driver/sim/simulator.h"

#include <poll.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "modbus_rtu_driver/sim/sim_device_commands.h"

namespace modbus_rtu_driver {

namespace {

SimClock::duration secs(double s) {
  return std::chrono::duration_cast<SimClock::duration>(std::chrono::duration<double>(s));
}

// The silence that ends a frame: t3.5, but at least 4 ms, as a pty delivers in bursts.
SimClock::duration silenceOf(const SimLineSettings& line) {
  return secs(std::max(simFrameGap(line), 0.004));
}

double monotonic(SimClock::time_point t) {
  return std::chrono::duration<double>(t.time_since_epoch()).count();
}

// steady_clock is CLOCK_MONOTONIC on Linux: the same clock as Python's time.monotonic(), so a
// benchmark can put a frame on the line next to its own events. A frame's first and last byte:
// for a request when they reached the simulator, for a reply when they were written.
void logFrame(const SimulatorOptions& o, const char* direction, const Bytes& frame,
              SimClock::time_point first, SimClock::time_point last) {
  if (!o.verbose) return;
  if (o.timestamps)
    std::printf("%s %.6f %.6f %s\n", direction, monotonic(first), monotonic(last),
                toHex(frame).c_str());
  else
    std::printf("%s %s\n", direction, toHex(frame).c_str());
  std::fflush(stdout);
}

}  // namespace

Simulator::Simulator(SimulatorConfig config, SimulatorOptions options)
    : config_(std::move(config)), options_(std::move(options)) {
  if (options_.control.empty()) options_.control = options_.link + ".ctl";
  for (const auto& e : config_.devices) devices_.push_back(makeSimDevice(e, config_.factory));
}

Simulator::~Simulator() {
  stop();
}

bool Simulator::start(std::string* error) {
  for (size_t i = 0; i < devices_.size(); ++i) {
    if (devices_[i]) continue;
    if (error) *error = "devices[" + std::to_string(i) + "]: unknown type";
    return false;
  }
  loadState(SimClock::now());
  if (!pty_.open(options_.link, config_.factory.baud, error, config_.factory.parity) ||
      !control_.open(options_.control, error) ||
      (options_.rtu_tcp_port >= 0 && !gateway_.listen(options_.rtu_tcp_port, error))) {
    stop();
    return false;
  }
  line_ = pty_.lineSettings();
  running_ = true;
  thread_ = std::thread(&Simulator::run, this);
  return true;
}

void Simulator::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  control_.close();
  gateway_.close();
  pty_.close();
  outgoing_.clear();
}

void Simulator::run() {
  while (running_) {
    // control_ belongs to this thread; the mutex guards the devices and the line state.
    std::vector<pollfd> fds{{pty_.fd(), POLLIN, 0}};
    control_.addPollFds(&fds);
    gateway_.addPollFds(&fds);
    timespec wait{};
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto ns =
          std::chrono::duration_cast<std::chrono::nanoseconds>(waitTime(SimClock::now())).count();
      wait.tv_sec = static_cast<time_t>(ns / 1'000'000'000);
      wait.tv_nsec = static_cast<long>(ns % 1'000'000'000);
    }
    ppoll(fds.data(), fds.size(), &wait, nullptr);
    const auto now = SimClock::now();
    // The pty is read before the lock: a system call has no place in it, and the fd is this
    // thread's (closed only after it ended).
    uint8_t buf[512];
    const ssize_t n = (fds[0].revents & POLLIN) ? read(pty_.fd(), buf, sizeof buf) : 0;
    std::lock_guard<std::mutex> lock(mutex_);
    if (power_cycle_requested_.exchange(false)) powerCycle(now);
    for (auto& d : devices_) d->tick(now);
    if (n > 0) take(buf, static_cast<size_t>(n), now);
    if (Bytes in; gateway_.receive(now, &in)) take(in.data(), in.size(), now);
    const bool silence = framer_.pending() && now - last_byte_ >= silenceOf(line_);
    for (const Bytes& frame : framer_.take(silence)) processFrame(frame, now);
    flushOutgoing(SimClock::now());
    control_.serve([this](const std::string& line) { return doCommand(line); });
  }
}

// How long the thread may sleep: until the next reply byte is due or the line falls silent
// (20 ms at most, so a power cycle asked for by a signal is not late).
SimClock::duration Simulator::waitTime(SimClock::time_point now) const {
  SimClock::time_point until = now + std::chrono::milliseconds(20);
  for (const Outgoing& o : outgoing_)
    until = std::min(until, o.start + o.per_byte * static_cast<long>(o.sent + 1));
  if (framer_.pending()) until = std::min(until, last_byte_ + silenceOf(line_));
  return std::max(until - now, SimClock::duration::zero());
}

void Simulator::take(const uint8_t* data, size_t size, SimClock::time_point now) {
  if (!framer_.pending()) rx_start_ = now;  // a new request starts on the wire
  framer_.push(data, size);
  last_byte_ = now;
  line_ = pty_.lineSettings();
}

void Simulator::processFrame(const Bytes& frame, SimClock::time_point now) {
  ++frames_;
  logFrame(options_, "rx", frame, framer_.pending() ? now : rx_start_, now);
  // Wire time of the request: it started with its first byte, or once the line was free.
  SimClock::time_point request_end = now;
  if (config_.pace) {
    request_end = std::max(rx_start_, line_free_) + secs(frame.size() * simCharacterTime(line_));
    rx_start_ = line_free_ = request_end;  // a next frame in the same burst follows this one
  }
  std::vector<SimDevice*> hearing;  // powered, answering, and at the line's settings
  for (auto& d : devices_)
    if (!d->silenced && d->understands(line_)) hearing.push_back(d.get());
  const uint8_t slave = frame[0], function = frame[1];
  const std::optional<Request> request = decodeRequest(frame);
  if (slave == kBroadcastAddress) return broadcast(request, hearing, now, request_end);

  std::vector<SimDevice*> targets;  // every device that takes this frame
  for (SimDevice* d : hearing)
    if (d->address() == slave || d->answersTo(slave, request ? &*request : nullptr))
      targets.push_back(d);
  if (targets.empty()) return;  // nobody at that address: silence
  if (targets.size() > 1) return collide(request, slave, function, targets, now, request_end);
  SimDevice* target = targets.front();

  if (chance(target->drop_request_percent)) {  // lost on the way: not heard, nothing done
    ++target->dropped_requests;
    return;
  }
  const double delay = target->replyDelay();  // a new return delay applies from the next request
  if (target->failing)
    return send(*target, encodeException(slave, function, kSlaveDeviceFailure), delay, request_end);
  if (!isKnownFunction(function))
    return send(*target, target->unknownFunction(slave, function), delay, request_end);
  if (!request)  // a known function whose layout does not add up (byte count vs quantity)
    return send(*target, encodeException(slave, function, kIllegalDataValue), delay, request_end);
  std::optional<Bytes> reply = target->handle(*request, now);
  if (!isReadFunction(request->function)) saveState();
  if (reply) send(*target, std::move(*reply), delay, request_end);
}

// Address 0 reaches every device that hears the line, as on a wire. Each applies it as its
// manual says (SimDevice::handleBroadcast): a write is applied and not answered, except where a
// manual says otherwise (the LC board answers its address commands); with more than one answer
// the replies collide (collideReplies).
void Simulator::broadcast(const std::optional<Request>& request,
                          const std::vector<SimDevice*>& hearing, SimClock::time_point now,
                          SimClock::time_point request_end) {
  if (!request) return;  // nobody answers a broadcast; an undecodable one changes nothing
  std::vector<Bytes> replies;
  SimDevice* first_answer = nullptr;
  for (SimDevice* d : hearing) {
    if (d->failing) continue;
    if (auto reply = d->handleBroadcast(*request, now)) {
      replies.push_back(std::move(*reply));
      if (!first_answer) first_answer = d;
    }
  }
  if (!isReadFunction(request->function)) saveState();
  if (!first_answer) return;  // no reply (first_answer is set with the first one)
  Bytes on_line = replies.size() == 1 ? std::move(replies[0]) : collideReplies(replies);
  send(*first_answer, std::move(on_line), first_answer->replyDelay(), request_end);
}

// An LD58A08 answering 0xFF and an LC board at 255 (or two devices at one address): each
// takes the request as if alone (a write lands on both) and both answer at once.
void Simulator::collide(const std::optional<Request>& request, uint8_t slave, uint8_t function,
                        const std::vector<SimDevice*>& targets, SimClock::time_point now,
                        SimClock::time_point request_end) {
  const double delay = targets.front()->replyDelay();
  std::vector<Bytes> replies;
  for (SimDevice* d : targets) {
    if (chance(d->drop_request_percent)) {
      ++d->dropped_requests;
      continue;
    }
    std::optional<Bytes> reply;
    if (d->failing)
      reply = encodeException(slave, function, kSlaveDeviceFailure);
    else if (!isKnownFunction(function))
      reply = d->unknownFunction(slave, function);
    else if (!request)
      reply = encodeException(slave, function, kIllegalDataValue);
    else
      reply = d->handle(*request, now);
    if (reply) replies.push_back(std::move(*reply));
  }
  if (request && !isReadFunction(request->function)) saveState();
  if (replies.empty()) return;
  Bytes on_line = replies.size() == 1 ? std::move(replies[0]) : collideReplies(replies);
  send(*targets.front(), std::move(on_line), delay, request_end);
}

// Several boards drive the line at once. A receiver gets neither reply: the model is the
// replies ANDed bit by bit (a driven 0 wins over the idle 1 on most transceivers), each board
// starting a bit after the one before, so the result is one byte longer than the longest
// reply. Should that ever form a valid frame, its CRC is spoiled: a collision is never clean.
Bytes collideReplies(const std::vector<Bytes>& replies) {
  size_t longest = 0;
  for (const Bytes& r : replies) longest = std::max(longest, r.size());
  Bytes line(longest + 1, 0xFF);
  for (size_t k = 0; k < replies.size(); ++k) {
    const unsigned shift = static_cast<unsigned>(k % 7);  // bits late
    uint16_t bits = 0xFFFF;                               // idle line before the reply
    for (size_t i = 0; i < line.size(); ++i) {
      const uint8_t byte = i < replies[k].size() ? replies[k][i] : 0xFF;
      bits = static_cast<uint16_t>((bits << 8) | byte);
      line[i] &= static_cast<uint8_t>(bits >> shift);
    }
  }
  if (hasValidCrc(line)) line.back() ^= 0x01;
  return line;
}

bool Simulator::chance(int percent) {
  return percent > 0 && static_cast<int>(random_() % 100) < percent;
}

// The reply faults of the control socket, in wire order: lost, another slave's address (a valid
// frame), cut short, bad CRC, noise after it, late.
void Simulator::send(SimDevice& device, Bytes reply, double delay,
                     SimClock::time_point request_end) {
  if (chance(device.drop_reply_percent)) {
    ++device.dropped_replies;
    return;
  }
  if (device.wrong_address_replies > 0) {
    --device.wrong_address_replies;
    reply[0] = static_cast<uint8_t>(reply[0] == 1 ? 2 : reply[0] - 1);
    reply.resize(reply.size() - 2);
    appendCrc(reply);
  }
  if (device.truncate_replies > 0) {
    --device.truncate_replies;
    reply.resize(std::max<size_t>(2, reply.size() / 2));
  }
  if (device.corrupt_replies > 0) {
    --device.corrupt_replies;
    reply.back() ^= 0xA5;
  }
  if (device.noise_replies > 0) {
    --device.noise_replies;
    for (uint8_t b : {0x00, 0xFF, 0x55, 0x03, 0x13}) reply.push_back(b);
  }
  if (device.late_replies > 0) {
    --device.late_replies;
    delay += device.late_ms / 1000.0;
  }
  Outgoing o;
  o.start = request_end + secs(delay);
  if (config_.pace) {
    const double ch = simCharacterTime(line_);
    o.start = std::max(o.start + secs(simFrameGap(line_)), line_free_);
    o.per_byte = secs(ch);
    line_free_ = o.start + secs(reply.size() * ch);
  }
  o.bytes = std::move(reply);
  outgoing_.push_back(std::move(o));
}

void Simulator::flushOutgoing(SimClock::time_point now) {
  for (auto it = outgoing_.begin(); it != outgoing_.end();) {
    Outgoing& o = *it;
    if (now < o.start) {
      ++it;
      continue;
    }
    size_t due = o.bytes.size();  // bytes whose last bit is on the wire by now
    if (o.per_byte.count() > 0)
      due = std::min(due, static_cast<size_t>((now - o.start) / o.per_byte));
    // The gateway forwards what the line carries, whether or not anyone reads the pty.
    if (o.sent < due) gateway_.send(o.bytes.data() + o.sent, due - o.sent);
    if (o.sent == 0 && due > 0) o.first_written = now;
    while (o.sent < due) {
      const ssize_t n = write(pty_.fd(), o.bytes.data() + o.sent, due - o.sent);
      if (n <= 0) {
        if (n < 0 && errno == EINTR) continue;
        o.sent = o.bytes.size();  // nobody reads the line: the rest is lost, as on a wire
        break;
      }
      o.sent += static_cast<size_t>(n);
    }
    if (o.sent < o.bytes.size()) {
      ++it;
      continue;
    }
    ++answered_;
    logFrame(options_, "tx", o.bytes, o.first_written, now);
    it = outgoing_.erase(it);
  }
}

void Simulator::powerCycle(SimClock::time_point now) {
  outgoing_.clear();  // a reply still waiting dies with the power
  for (auto& d : devices_) d->powerCycle(now);
  saveState();
}

// Written only when it changed, through a temporary file, so a crash never leaves half a file.
void Simulator::saveState() {
  if (options_.state_file.empty()) return;
  YAML::Node root;
  for (auto& d : devices_) {
    YAML::Node n;
    n["type"] = d->type();
    d->saveState(n);
    root["devices"].push_back(n);
  }
  YAML::Emitter emitter;
  emitter << root;
  const std::string text = std::string(emitter.c_str()) + "\n";
  if (text == state_text_) return;
  const std::string tmp = options_.state_file + ".tmp";
  std::ofstream(tmp) << text;
  if (std::rename(tmp.c_str(), options_.state_file.c_str()) == 0) state_text_ = text;
}

// Devices are matched by index and type; a device whose entry does not fit keeps the config.
void Simulator::loadState(SimClock::time_point now) {
  if (options_.state_file.empty() || access(options_.state_file.c_str(), R_OK) != 0) return;
  try {
    const YAML::Node root = YAML::LoadFile(options_.state_file);
    const YAML::Node list = root["devices"];
    for (size_t i = 0; list.IsSequence() && i < devices_.size() && i < list.size(); ++i)
      if (list[i]["type"].as<std::string>("") == devices_[i]->type())
        devices_[i]->loadState(list[i], now);
  } catch (const YAML::Exception& e) {
    std::fprintf(stderr, "ignoring the state file %s: %s\n", options_.state_file.c_str(), e.what());
  }
}

std::string Simulator::command(const std::string& line) {
  std::lock_guard<std::mutex> lock(mutex_);
  return doCommand(line);
}

SimDevice* Simulator::find(const std::string& name) {
  long v = 0;
  if (name.size() > 1 && name[0] == '#') {
    if (!parseControlNumber(name.substr(1), 0, static_cast<long>(devices_.size()) - 1, &v))
      return nullptr;
    return devices_[static_cast<size_t>(v)].get();
  }
  if (!parseControlNumber(name, 0, 255, &v)) return nullptr;
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
    if (in >> ms_text && !parseControlNumber(ms_text, 0, 600000, &ms))
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
           std::string(kSimGetSetUsage);
  if (!isSimDeviceCommand(verb)) return "error unknown command '" + verb + "' (try help)";
  in >> name;
  SimDevice* d = find(name);
  if (!d) return "error no device '" + name + "' (#index or address; see info)";
  bool stored = false;
  std::string reply = simDeviceCommand(verb, *d, in, SimClock::now(), &stored);
  if (stored) saveState();
  return reply;
}

}  // namespace modbus_rtu_driver
