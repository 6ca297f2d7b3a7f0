// The slave role: the node answers a Modbus master (such as the DM500 controller) on its own
// serial line. libmodbus's server side holds the tables (modbus_mapping_t) and builds every
// reply (modbus_reply); frames are cut by our own reader, because libmodbus 3.1.6's receive can
// swallow a valid request that follows one for another slave id (libmodbus issues 709, 799).
// One thread owns the port and the mapping; others hand it changes through a queue.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/core/config/slave_config.h"
#include "modbus_rtu_driver/core/modbus/frame.h"
#include "modbus_rtu_driver/core/modbus/request_framer.h"

typedef struct _modbus modbus_t;                    // NOLINT: libmodbus's names
typedef struct _modbus_mapping_t modbus_mapping_t;  // NOLINT

namespace modbus_rtu_driver {

// A write the master made (after it was applied and answered).
struct SlaveWrite {
  Table table = Table::kCoil;  // kCoils or kHoldingRegisters
  uint16_t address = 0;
  std::vector<uint16_t> values;  // coil states 0/1 or register values
  bool broadcast = false;
};

// The DM500 puts macro buffer bytes into registers low byte first: bytes 7, 8 travel as 0x0807.
std::vector<uint8_t> registersToMacroBytes(const std::vector<uint16_t>& registers);

struct SlaveStats {
  uint64_t requests_served = 0;  // frames for our id answered (exceptions included)
  uint64_t exceptions_sent = 0;
  uint64_t broadcasts = 0;       // applied, not answered
  uint64_t crc_errors = 0;       // frames (or noise) dropped for a bad CRC
  uint64_t other_slave = 0;      // valid frames for other ids, ignored
  uint64_t not_requests = 0;     // function code 0x80-0xFF: an exception reply, ignored
  double since_last_heard = -1;  // s since the last valid frame for us; -1 = never
  bool port_open = false;
  std::string port_error;
};

class SlaveServer {
 public:
  using WriteCallback = std::function<void(const SlaveWrite&)>;

  SlaveServer(SlaveConfig config, WriteCallback on_write);
  ~SlaveServer();
  SlaveServer(const SlaveServer&) = delete;
  SlaveServer& operator=(const SlaveServer&) = delete;

  // Starts the thread; it opens the port (and reopens it with backoff when it fails).
  void start();
  void stop();

  // Sets values the master will read. Empty when accepted (applied before the next frame),
  // else a message naming the range.
  std::string set(Table table, uint16_t address, const std::vector<uint16_t>& values);
  SlaveStats stats() const;

  // What the thread does with bytes from the line, callable without it (tests, fuzz target):
  // opens the port; frames `data` (`silence`: the line went quiet after it) and answers them.
  bool openPort(std::string* error);
  void handleInput(const uint8_t* data, size_t size, bool silence);
  const SlaveConfig& config() const { return config_; }

 private:
  struct Change {
    Table table;
    uint16_t address;
    std::vector<uint16_t> values;
  };
  bool open(std::string* error);
  void close();
  void run();
  void applyChanges();
  void serve(const Bytes& frame);
  uint8_t predictException(const Bytes& frame) const;
  uint16_t tableSize(Table table) const;

  SlaveConfig config_;
  WriteCallback on_write_;
  modbus_t* ctx_ = nullptr;
  modbus_mapping_t* mapping_ = nullptr;
  std::thread thread_;
  std::atomic<bool> running_{false};
  mutable std::mutex mutex_;  // guards changes_ and stats_
  std::vector<Change> changes_;
  SlaveStats stats_;
  std::chrono::steady_clock::time_point last_heard_{};
  bool heard_ = false;
  RequestFramer framer_;
  std::chrono::steady_clock::time_point last_byte_{};
};

}  // namespace modbus_rtu_driver
