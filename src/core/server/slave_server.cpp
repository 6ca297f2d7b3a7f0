#include "modbus_rtu_driver/core/server/slave_server.h"

#include <modbus/modbus.h>
#include <unistd.h>

#include <cerrno>

#include "modbus_rtu_driver/core/link/fd_io.h"
#include "modbus_rtu_driver/core/link/serial_port.h"

namespace modbus_rtu_driver {

namespace {
using Steady = std::chrono::steady_clock;
}  // namespace

std::vector<uint8_t> registersToMacroBytes(const std::vector<uint16_t>& registers) {
  std::vector<uint8_t> bytes;
  for (uint16_t r : registers) {
    bytes.push_back(static_cast<uint8_t>(r & 0xFF));
    bytes.push_back(static_cast<uint8_t>(r >> 8));
  }
  return bytes;
}

SlaveServer::SlaveServer(SlaveConfig config, WriteCallback on_write)
    : config_(std::move(config)), on_write_(std::move(on_write)) {}

SlaveServer::~SlaveServer() {
  stop();
}

uint16_t SlaveServer::tableSize(Table t) const {
  switch (t) {
    case Table::kCoil:
      return config_.coils;
    case Table::kDiscreteInput:
      return config_.discrete_inputs;
    case Table::kHoldingRegister:
      return config_.holding_registers;
    case Table::kInputRegister:
      return config_.input_registers;
  }
  return 0;
}

std::string SlaveServer::set(Table table, uint16_t address, const std::vector<uint16_t>& values) {
  const uint16_t size = tableSize(table);
  if (values.empty()) return std::string("values: empty, give at least one value");
  if (static_cast<uint32_t>(address) + values.size() > size)
    return std::string("address: ") + std::to_string(address) + " with " +
           std::to_string(values.size()) + " value(s) is outside " + tableName(table) + " 0-" +
           std::to_string(static_cast<int>(size) - 1);
  const bool bits = table == Table::kCoil || table == Table::kDiscreteInput;
  if (bits)
    for (uint16_t v : values)
      if (v > 1) return "values: coil and input states are 0 or 1";
  std::lock_guard<std::mutex> lock(mutex_);
  changes_.push_back({table, address, values});
  return {};
}

SlaveStats SlaveServer::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  SlaveStats s = stats_;
  if (heard_)
    s.since_last_heard = std::chrono::duration<double>(Steady::now() - last_heard_).count();
  return s;
}

void SlaveServer::start() {
  if (running_) return;
  running_ = true;
  thread_ = std::thread(&SlaveServer::run, this);
}

void SlaveServer::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  close();
  if (mapping_) modbus_mapping_free(mapping_);
  mapping_ = nullptr;
}

bool SlaveServer::open(std::string* error) {
  ctx_ = openSerialPort(config_.link, error);
  if (!ctx_) return false;
  modbus_set_slave(ctx_, config_.slave_id);
  if (!mapping_)
    mapping_ = modbus_mapping_new(config_.coils, config_.discrete_inputs, config_.holding_registers,
                                  config_.input_registers);
  return mapping_ != nullptr;
}

void SlaveServer::close() {
  closeSerialPort(ctx_);
  ctx_ = nullptr;
}

void SlaveServer::applyChanges() {
  std::vector<Change> changes;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    changes.swap(changes_);
  }
  for (const Change& c : changes) {
    for (size_t i = 0; i < c.values.size(); ++i) {
      const size_t a = c.address + i;
      switch (c.table) {
        case Table::kCoil:
          mapping_->tab_bits[a] = static_cast<uint8_t>(c.values[i]);
          break;
        case Table::kDiscreteInput:
          mapping_->tab_input_bits[a] = static_cast<uint8_t>(c.values[i]);
          break;
        case Table::kHoldingRegister:
          mapping_->tab_registers[a] = c.values[i];
          break;
        case Table::kInputRegister:
          mapping_->tab_input_registers[a] = c.values[i];
          break;
      }
    }
  }
}

void SlaveServer::run() {
  double backoff = 0.2;
  while (running_) {
    if (!ctx_) {
      std::string error;
      const bool ok = open(&error);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.port_open = ok;
        stats_.port_error = error;
      }
      if (!ok) {
        std::this_thread::sleep_for(std::chrono::duration<double>(backoff));
        backoff = std::min(5.0, backoff * 2);
        continue;
      }
      backoff = 0.2;
    }
    applyChanges();
    const int fd = modbus_get_socket(ctx_);
    const int ready = waitReadable(fd, 0.002);
    bool got = false;
    if (ready > 0) {
      uint8_t buf[512];
      const ssize_t n = read(fd, buf, sizeof buf);
      if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) {
        close();  // readable but nothing to read: the port went away, reopen
        continue;
      }
      if (n > 0) {
        last_byte_ = Steady::now();
        got = true;
        handleInput(buf, static_cast<size_t>(n), false);
      }
    }
    // t3.5 ends a frame; ptys and USB adapters deliver in bursts, so never less than 4 ms.
    const double gap = std::max(effectiveMinGap(config_.link), 0.004);
    const bool silence = !got && framer_.pending() &&
                         Steady::now() - last_byte_ > std::chrono::duration<double>(gap);
    if (silence) handleInput(nullptr, 0, true);
  }
}

bool SlaveServer::openPort(std::string* error) {
  return ctx_ || open(error);
}

void SlaveServer::handleInput(const uint8_t* data, size_t size, bool silence) {
  if (size) framer_.push(data, size);
  for (const Bytes& frame : framer_.take(silence)) serve(frame);
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.crc_errors = framer_.dropped();
}

// The exception this frame deserves (0 = a normal reply), sent by serve() itself, so it is counted
// and a failed write is never reported as written.
uint8_t SlaveServer::predictException(const Bytes& f) const {
  const auto request = decodeRequest(f);
  // A known function whose layout does not add up (byte count vs quantity) is a bad value.
  if (!request) return isKnownFunction(f[1]) ? kIllegalDataValue : kIllegalFunction;
  const Request& r = *request;
  if (r.function == FunctionCode::kWriteSingleCoil && r.values[0] > 1) return kIllegalDataValue;
  if (r.count < 1 || r.count > maxCount(r.function)) return kIllegalDataValue;
  if (static_cast<uint32_t>(r.address) + r.count > tableSize(tableOf(r.function)))
    return kIllegalDataAddress;
  return 0;
}

void SlaveServer::serve(const Bytes& frame) {
  const uint8_t slave = frame[0];
  const bool broadcast = slave == kBroadcastAddress;
  if (!broadcast && slave != config_.slave_id) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.other_slave;
    return;
  }
  // Codes 0x80-0xFF are exception replies (another device's, or noise), never requests: no
  // answer. (libmodbus's modbus_reply_exception would add 0x80 and send a wrong function code.)
  if (frame[1] & 0x80) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.not_requests;
    return;
  }
  const uint8_t exception = predictException(frame);
  if (exception) {
    // For an unknown function or a bad quantity, modbus_reply (3.1.6) sleeps a response timeout
    // and flushes the input before answering, losing whatever the master sends next (found by
    // the DM500 garbage rostest); this call answers at once.
    if (!broadcast) modbus_reply_exception(ctx_, frame.data(), exception);
  } else {
    // libmodbus writes the mapping and the reply (none for a broadcast).
    modbus_reply(ctx_, frame.data(), static_cast<int>(frame.size()), mapping_);
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_heard_ = Steady::now();
    heard_ = true;
    if (broadcast) {
      ++stats_.broadcasts;
    } else {
      ++stats_.requests_served;
      if (exception) ++stats_.exceptions_sent;
    }
  }
  const auto request = decodeRequest(frame);
  if (exception || !request || isReadFunction(request->function) || !on_write_) return;
  SlaveWrite w;
  w.table = tableOf(request->function);
  w.address = request->address;
  w.values = request->values;
  w.broadcast = broadcast;
  on_write_(w);
}

}  // namespace modbus_rtu_driver
