// A Modbus TCP server on one thread (a poll loop over its sockets): the listening socket, the
// allow list and the client bound applied at accept, per-client MBAP framing (core/modbus/mbap.h),
// requests decoded and validated (frame.h, Request::validate) before a handler sees them, and
// replies sent whenever the handler gives them, from any thread, so the loop never waits for a
// bus. ROS-free: the node's share and the simulator's TCP side use it.
//
// What the server answers itself: with refuse_writes, a write function (05, 06, 15, 16) -> 01
// before any other check, so a malformed write is refused as a write (not 02/03: the client
// learns that no write can pass, not how to fix this one); a function it does not know -> 01;
// a start address
// plus quantity past 65535 -> 02 (the application protocol's order: quantity first, then the
// address range); a PDU that does not fit its function or a request Request::validate()
// refuses otherwise -> 03 (01 for a read at unit 0, which nobody could answer). A header that
// is not Modbus (protocol id not 0, length outside 2-254) closes that client: its byte stream
// cannot be resynchronised.
//
// Connections: TCP keep-alive on every accepted socket (a peer that vanished is found within
// about a minute); a client with no request waiting for its answer that sends nothing for
// `idle_timeout` s (silent, or stopped halfway through a frame) is closed, freeing its slot. A
// client that half-closes (shutdown(SHUT_WR)) after its requests still gets their answers; the
// connection is closed once they are sent.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/core/config/share_config.h"
#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

// Keep-alive on an accepted socket: first probe after 30 s of silence, then every 10 s, the
// connection dropped after 3 unanswered probes.
constexpr int kKeepAliveIdle = 30, kKeepAliveInterval = 10, kKeepAliveCount = 3;

class ModbusTcpServer {
 public:
  using ClientId = uint64_t;
  // One valid request from a client.
  struct Incoming {
    ClientId client = 0;
    uint16_t transaction = 0;
    Request request;
    std::string peer;  // the client's address, "127.0.0.1"
  };
  // Runs on the server's thread; must not block. Answers with reply() now or later (any thread).
  using Handler = std::function<void(const Incoming&)>;

  struct PeerCounts {  // per client address, over all its connections
    uint64_t connections = 0;
    uint64_t requests = 0;  // complete frames received
    uint64_t exceptions = 0;
  };
  struct Stats {
    uint64_t accepted = 0, refused_not_allowed = 0, refused_too_many = 0;
    uint64_t malformed = 0;    // clients closed for a header that is not Modbus TCP
    uint64_t idle_closed = 0;  // clients closed after idle_timeout with nothing pending
    uint64_t half_closed = 0;  // clients that sent FIN with answers still to come
    size_t connected = 0;
    std::map<std::string, PeerCounts> peers;
  };

  ModbusTcpServer(TcpServerOptions options, Handler handler);
  ~ModbusTcpServer();
  ModbusTcpServer(const ModbusTcpServer&) = delete;
  ModbusTcpServer& operator=(const ModbusTcpServer&) = delete;

  // Checks the options, binds, listens and starts the thread. False with a message.
  bool start(std::string* error);
  // Binds a socket to host:port as start() does and closes it: true when a server could listen
  // there now; false with the reason, `in_use` set for EADDRINUSE. A bus node asks before it
  // touches the bus (a start may still lose the port to a program that takes it meanwhile).
  static bool canListen(const std::string& host, uint16_t port, std::string* error, bool* in_use);
  void stop();  // closes every socket; later replies are dropped
  uint16_t port() const { return bound_port_; }
  // After a failed start: the address was taken (EADDRINUSE), by another bus's share or any
  // other program, so the caller can say which setting to change.
  bool addressInUse() const { return address_in_use_; }

  // Sends the answer to `in`: an RTU ADU (encodeReply / encodeException; its CRC is dropped)
  // carried with the request's transaction id. Any thread; dropped when the client has gone.
  void reply(const Incoming& in, const Bytes& rtu_adu);
  void replyException(const Incoming& in, uint8_t code);
  // Closes every client connection (a gateway reboot); the server keeps listening.
  void dropClients();
  Stats stats() const;

 private:
  struct Client {
    int fd = -1;
    std::string peer;
    Bytes input, output;
    std::chrono::steady_clock::time_point last_activity;  // last bytes in, or last answer out
    int unanswered = 0;        // requests taken whose answer has not been given yet
    bool read_closed = false;  // the client sent FIN: answer what it asked, then close
  };
  struct AllowRule {
    uint32_t network, mask;
  };

  void run();
  void acceptClient();
  void receive(ClientId id);
  void handleFrame(ClientId id, const Bytes& adu);
  void flush(ClientId id);
  void closeClient(ClientId id);  // mutex_ held
  // Closes idle clients and half-closed ones with nothing left to send; returns the poll
  // timeout (ms, -1 = none) until the next idle deadline. mutex_ held.
  int closeFinished(std::chrono::steady_clock::time_point now);
  void wake() const;

  TcpServerOptions options_;
  Handler handler_;
  std::vector<AllowRule> allow_;
  int listen_fd_ = -1, wake_fd_ = -1;
  uint16_t bound_port_ = 0;
  bool address_in_use_ = false;
  std::atomic<bool> running_{false}, drop_requested_{false};
  std::thread thread_;
  mutable std::mutex mutex_;  // clients_ and stats_ (the loop and reply() share them)
  std::map<ClientId, Client> clients_;
  ClientId next_id_ = 1;
  Stats stats_;
};

}  // namespace modbus_rtu_driver
