#include "modbus_rtu_driver/sim/sim_control_socket.h"

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace modbus_rtu_driver {

namespace {

constexpr size_t kMaxLine = 4096;

}  // namespace

bool SimControlSocket::open(const std::string& path, std::string* error) {
  sockaddr_un addr{};
  if (path.size() >= sizeof addr.sun_path) {
    if (error) *error = "control socket path too long: " + path;
    return false;
  }
  path_ = path;
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path.c_str());
  // A socket there that accepts a connection is a running simulator's: refused, never taken
  // over. One that refuses is stale: replaced.
  const int probe = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const bool answers =
      probe >= 0 && connect(probe, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  if (probe >= 0) ::close(probe);
  if (answers) {
    if (error)
      *error = "control socket " + path +
               " belongs to a running simulator (it accepts connections): give each simulator "
               "its own --control";
    return false;
  }
  listen_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  unlink(path.c_str());  // a stale socket of an earlier run
  if (listen_fd_ < 0 || bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      listen(listen_fd_, 16) != 0) {
    if (error) *error = "cannot listen on " + path + ": " + std::strerror(errno);
    return false;
  }
  struct stat st {};
  if (stat(path.c_str(), &st) == 0) inode_ = {st.st_dev, st.st_ino};
  return true;
}

void SimControlSocket::close() {
  for (const Client& c : clients_) ::close(c.fd);
  clients_.clear();
  if (listen_fd_ < 0) return;
  ::close(listen_fd_);
  listen_fd_ = -1;
  struct stat st {};
  if (inode_.second != 0 && stat(path_.c_str(), &st) == 0 &&
      std::make_pair(st.st_dev, st.st_ino) == inode_)
    unlink(path_.c_str());
  inode_ = {};
}

void SimControlSocket::addPollFds(std::vector<pollfd>* fds) const {
  fds->push_back({listen_fd_, POLLIN, 0});
  for (const Client& c : clients_) fds->push_back({c.fd, POLLIN, 0});
}

void SimControlSocket::serve(const std::function<std::string(const std::string&)>& answer) {
  for (int c; (c = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC)) >= 0;)
    clients_.push_back({c, {}});
  for (size_t i = 0; i < clients_.size();) {
    Client& client = clients_[i];
    char buf[512];
    const ssize_t n = read(client.fd, buf, sizeof buf);
    bool drop = n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
    if (n > 0) client.input.append(buf, static_cast<size_t>(n));
    for (size_t nl; !drop && (nl = client.input.find('\n')) != std::string::npos;) {
      const std::string reply = answer(client.input.substr(0, nl)) + "\n";
      client.input.erase(0, nl + 1);
      drop = ::send(client.fd, reply.data(), reply.size(), MSG_NOSIGNAL) !=
             static_cast<ssize_t>(reply.size());
    }
    if (!drop && client.input.size() > kMaxLine) drop = true;  // no line end in sight
    if (drop) {
      ::close(client.fd);
      clients_.erase(clients_.begin() + static_cast<long>(i));
    } else {
      ++i;
    }
  }
}

}  // namespace modbus_rtu_driver
