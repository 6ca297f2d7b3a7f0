// Transport overhead: transactions per second of ModbusTcpLink against a plain libmodbus TCP
// client loop (modbus_new_tcp), both to the same libmodbus TCP server in this process; and of
// RtuOverTcpLink against RtuLink, both to the same simulator (its RTU-over-TCP gateway and its
// pty). The servers answer at once, so the figures are the clients' software and socket costs.
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bench_common.h"
#include "modbus_rtu_driver/core/link/make_link.h"
#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

namespace {

using Steady = std::chrono::steady_clock;

// libmodbus's own TCP server on 127.0.0.1, one client at a time, until stopped.
class LibmodbusTcpServer {
 public:
  LibmodbusTcpServer() {
    ctx_ = modbus_new_tcp("127.0.0.1", 0);
    mapping_ = modbus_mapping_new(100, 100, 100, 100);
    listen_fd_ = modbus_tcp_listen(ctx_, 1);
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(reinterpret_cast<sockaddr_in&>(addr).sin_port);
    thread_ = std::thread([this] { run(); });
  }
  ~LibmodbusTcpServer() {
    stop_ = true;
    thread_.join();
    close(listen_fd_);
    modbus_mapping_free(mapping_);
    modbus_free(ctx_);
  }
  int port() const { return port_; }

 private:
  void run() {
    while (!stop_) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (poll(&p, 1, 20) <= 0) continue;
      int fd = listen_fd_;
      if (modbus_tcp_accept(ctx_, &fd) < 0) continue;
      uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
      for (int rc; (rc = modbus_receive(ctx_, query)) != -1;)
        if (rc > 0) modbus_reply(ctx_, query, rc, mapping_);
      close(modbus_get_socket(ctx_));
    }
  }

  modbus_t* ctx_ = nullptr;
  modbus_mapping_t* mapping_ = nullptr;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The best of 4 rounds of `once` (rounds of each side alternate with the caller's others).
struct Best {
  double value = 0;
  void round(double seconds, const std::function<bool()>& once) {
    value = std::max(value, transactionRate(seconds, once));
  }
};

// While it lives, this thread and the threads it starts run on one CPU: whether a client and its
// server share a CPU moves single rounds by up to 1.5 x (a wake-up across CPUs costs more), so
// a comparison of the software alone pins both.
class PinnedToOneCpu {
 public:
  PinnedToOneCpu() {
    if (sched_getaffinity(0, sizeof saved_, &saved_) != 0) return;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (!CPU_ISSET(cpu, &saved_)) continue;
      cpu_set_t one;
      CPU_ZERO(&one);
      CPU_SET(cpu, &one);
      pinned_ = sched_setaffinity(0, sizeof one, &one) == 0;
      return;
    }
  }
  ~PinnedToOneCpu() {
    if (pinned_) sched_setaffinity(0, sizeof saved_, &saved_);
  }
  PinnedToOneCpu(const PinnedToOneCpu&) = delete;
  PinnedToOneCpu& operator=(const PinnedToOneCpu&) = delete;

 private:
  cpu_set_t saved_{};
  bool pinned_ = false;
};

// Plain libmodbus TCP and ModbusTcpLink, each against a server of its own started pinned with
// it, in alternating rounds.
void onOneCpu(const Request& request, double seconds, Best* plain, Best* ours) {
  const PinnedToOneCpu pinned;
  LibmodbusTcpServer server;
  LinkConfig config;
  config.min_gap = 1e-6;
  config.port = "tcp://127.0.0.1:" + std::to_string(server.port());
  for (int round = 0; round < 4; ++round) {
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", server.port());
    modbus_connect(ctx);
    modbus_set_slave(ctx, 2);
    plain->round(seconds / 4, [&] { return plainLibmodbus(ctx, request); });
    modbus_close(ctx);
    modbus_free(ctx);
    const std::unique_ptr<Link> link = makeLink(config);
    std::string error;
    if (!link->connect(&error)) std::fprintf(stderr, "%s\n", error.c_str());
    ours->round(seconds / 4, [&] { return link->execute(request).ok(); });
  }
}

}  // namespace

void benchmarkTransports(const std::string& dir, double seconds, std::ofstream& csv) {
  const std::vector<std::pair<const char*, Request>> ops = {
      {"01 read 8 coils", Request::readCoils(2, 0, 8)},
      {"03 read 3 holding", Request::readHoldingRegisters(2, 0, 3)},
      {"05 write coil", Request::writeSingleCoil(2, 1, true)},
      {"16 write 3 holding", Request::writeMultipleRegisters(2, 0, {2500, 2000, 1600})},
  };
  LibmodbusTcpServer tcp_server;
  SimulatorConfig config;
  config.factory.baud = 115200;
  config.devices = {{"yespeed_pdu", 2}};
  SimulatorOptions options;
  options.link = dir + "/transports";
  options.rtu_tcp_port = 0;
  Simulator sim(config, options);
  std::string error;
  if (!sim.start(&error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return;
  }
  LinkConfig base;
  base.baud = 115200;
  base.min_gap = 1e-6;  // libmodbus keeps no gap: compare the software alone
  LinkConfig tcp = base, rtu_tcp = base, serial = base;
  tcp.port = "tcp://127.0.0.1:" + std::to_string(tcp_server.port());
  rtu_tcp.port = "rtu+tcp://127.0.0.1:" + std::to_string(sim.rtuTcpPort());
  serial.port = options.link;

  std::printf(
      "## Transport overhead (servers answering at once, loopback, best of 4 rounds of %g s)\n\n",
      seconds / 4);
  std::printf(
      "| function | plain libmodbus TCP [tx/s] | ModbusTcpLink [tx/s] | ratio | the same on one "
      "CPU: plain [tx/s] | ModbusTcpLink [tx/s] | ratio | RtuOverTcpLink [tx/s] (sim gateway) | "
      "RtuLink [tx/s] (sim pty) | ratio |\n|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& [name, request] : ops) {
    // What the lambdas below use: C++17 lets no lambda capture a structured binding (g++ allows
    // it, clang 14's clang-tidy reports an error).
    const auto& op = request;
    Best plain, ours_tcp, ours_rtu_tcp, ours_serial;
    for (int round = 0; round < 4; ++round) {
      modbus_t* ctx = modbus_new_tcp("127.0.0.1", tcp_server.port());
      modbus_connect(ctx);
      modbus_set_slave(ctx, 2);
      plain.round(seconds / 4, [&] { return plainLibmodbus(ctx, op); });
      modbus_close(ctx);
      modbus_free(ctx);
      for (auto [config_of, best] : {std::pair{&tcp, &ours_tcp}, std::pair{&rtu_tcp, &ours_rtu_tcp},
                                     std::pair{&serial, &ours_serial}}) {
        const std::unique_ptr<Link> link = makeLink(*config_of);
        if (!link->connect(&error)) std::fprintf(stderr, "%s\n", error.c_str());
        best->round(seconds / 4, [&] { return link->execute(op).ok(); });
      }
    }
    Best plain_one, ours_one;
    onOneCpu(request, seconds, &plain_one, &ours_one);
    const auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
    std::printf("| %s | %.0f | %.0f | %.2f | %.0f | %.0f | %.2f | %.0f | %.0f | %.2f |\n", name,
                plain.value, ours_tcp.value, ratio(plain.value, ours_tcp.value), plain_one.value,
                ours_one.value, ratio(plain_one.value, ours_one.value), ours_rtu_tcp.value,
                ours_serial.value, ratio(ours_serial.value, ours_rtu_tcp.value));
    csv << "transport_tcp," << name << "," << plain.value << "," << ours_tcp.value << ","
        << ratio(plain.value, ours_tcp.value) << "\n";
    csv << "transport_tcp_one_cpu," << name << "," << plain_one.value << "," << ours_one.value
        << "," << ratio(plain_one.value, ours_one.value) << "\n";
    csv << "transport_rtu_tcp," << name << "," << ours_serial.value << "," << ours_rtu_tcp.value
        << "," << ratio(ours_serial.value, ours_rtu_tcp.value) << "\n";
  }
  std::printf(
      "\nratio = plain libmodbus TCP / ModbusTcpLink (the first), RtuLink over the pty / "
      "RtuOverTcpLink through the simulator's gateway (the second): above 1 = slower than the "
      "reference. 0 = a transaction failed. On one CPU: the client and a server of its own pinned "
      "to one CPU, so whether the two threads share a CPU (which moves single rounds by up to "
      "1.5 x) is the same for both sides and the ratio is the software's.\n\n");
}

}  // namespace modbus_rtu_driver
