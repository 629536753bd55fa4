#include "limited_server.hpp"

#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>

#include "connection_threads.hpp"

namespace robodiff::server {
namespace {

thread_local const ConnectionStream* current_connection = nullptr;

}  // namespace

LimitedServer::LimitedServer(const ConnectionLimits& limits, std::size_t max_connections)
    : limits_(limits), max_connections_(max_connections), stop_fd_(::eventfd(0, EFD_CLOEXEC)) {
  new_task_queue = [max_connections] { return new ConnectionThreads(max_connections); };
  set_keep_alive_max_count(1);
  set_address_family(AF_INET);
  set_socket_options([](socket_t sock) {
    const int one = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  });
}

LimitedServer::~LimitedServer() {
  if (stop_fd_ >= 0) ::close(stop_fd_);
}

int LimitedServer::bindTo(const std::string& host, int port) {
  if (stop_fd_ < 0) return -1;  // errno from eventfd
  errno = 0;
  const int bound = port == 0 ? bind_to_any_port(host) : (bind_to_port(host, port) ? port : -1);
  if (bound <= 0) return -1;
  // httplib listens with a backlog of 5: the clients waiting for a connection thread wait here.
  ::listen(svr_sock_, static_cast<int>(max_connections_));
  return bound;
}

void LimitedServer::stopAll() {
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = ::write(stop_fd_, &one, sizeof one);
  stop();
}

std::string LimitedServer::currentProblem() {
  return current_connection ? current_connection->problem() : std::string();
}

bool LimitedServer::process_and_close_socket(socket_t sock) {
  ConnectionStream stream(sock, limits_, stop_fd_);
  current_connection = &stream;
  bool closed_by_client = false;
  const bool ok = process_request(stream, /*close_connection=*/true, closed_by_client, [](httplib::Request&) {});
  current_connection = nullptr;
  stream.close();
  return ok;
}

}  // namespace robodiff::server
