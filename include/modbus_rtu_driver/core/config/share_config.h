// The share's settings (docs/share.md), with the TCP server's they hold, beside the other
// settings: the bus node's configuration holds them without the gateway, the scheduler and the
// server that use them (core/server).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace modbus_rtu_driver {

struct TcpServerOptions {
  std::string host = "127.0.0.1";  // IPv4 address to listen on (0.0.0.0: every interface)
  uint16_t port = 1502;            // 0: any free port (tests; see ModbusTcpServer::port())
  // Clients allowed to connect: IPv4 addresses or CIDR blocks ("10.0.0.0/8", "0.0.0.0/0" for
  // everyone). Others are closed at accept.
  std::vector<std::string> allow{"127.0.0.1"};
  int max_clients = 4;  // connections at once; a further one is closed at accept
  // s a client with no answer pending may stay silent before it is closed; 0 = never.
  double idle_timeout = 60.0;
  // Every write function code answered with exception 01 before it is decoded (the share's
  // read_only; not a YAML key of its own).
  bool refuse_writes = false;
};

// "127.0.0.1:1502" -> host and port (1-65535). False with a message.
bool parseListenAddress(const std::string& text, std::string* host, uint16_t* port,
                        std::string* error);
// An allow-list entry: "a.b.c.d" or "a.b.c.d/n" (n 0-32). False with a message.
bool parseAllowEntry(const std::string& entry, uint32_t* network, uint32_t* mask,
                     std::string* error);

struct ShareConfig {
  bool enabled = false;
  TcpServerOptions server;  // listen, allow, max_clients
  // Write functions (05, 06, 15, 16) answered with exception 01 before any check of their
  // fields (the server's refuse_writes).
  bool read_only = false;
  int max_queue = 16;                 // requests waiting for or on the bus, all clients together
  double broadcast_turnaround = 0.1;  // s of silence on the bus after a broadcast, 0-1
  // s: every request is answered within this (docs/share.md, "How long an answer takes"); one
  // that cannot start in time gets 0B, unsent. 0 = twice the longest transaction.
  double answer_within = 0.0;
};
constexpr double kMaxBroadcastTurnaround = 1.0;  // s
constexpr double kMinAnswerWithin = 0.001;       // s
constexpr double kMaxAnswerWithin = 60.0;        // s

}  // namespace modbus_rtu_driver
