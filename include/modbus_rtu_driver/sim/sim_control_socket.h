// The simulator's control socket: a Unix stream socket, one text command per line, one reply
// line each ("ok ..." or "error <message>"; the commands: simulator.cpp and
// sim_device_commands.h). Served by the simulator's line thread, which polls its fds with the
// pty's, so the commands need no locks of their own.
#pragma once

#include <poll.h>
#include <sys/types.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace modbus_rtu_driver {

class SimControlSocket {
 public:
  SimControlSocket() = default;
  ~SimControlSocket() { close(); }
  SimControlSocket(const SimControlSocket&) = delete;
  SimControlSocket& operator=(const SimControlSocket&) = delete;

  // Listens at `path`. Refuses a socket there that a running simulator answers on (given the
  // same --control with another --link); one that refuses connections is stale: replaced.
  bool open(const std::string& path, std::string* error);
  // Closes the socket and its clients; removes only the socket this run made, never one that
  // replaced it since.
  void close();
  // The listening socket's and the clients' fds, for the line thread's poll.
  void addPollFds(std::vector<pollfd>* fds) const;
  // Accepts new clients, reads what came, answers each whole line with `answer`; drops a client
  // that closed, failed, or sent an over-long line.
  void serve(const std::function<std::string(const std::string&)>& answer);

 private:
  struct Client {
    int fd;
    std::string input;
  };
  std::string path_;
  int listen_fd_ = -1;
  std::pair<dev_t, ino_t> inode_{};  // the socket this run made (0: none)
  std::vector<Client> clients_;
};

}  // namespace modbus_rtu_driver
