#pragma once
// httplib's server with robodiff's connection handling: each connection is read and
// written through a ConnectionStream (the head's size and time limits, the response's
// time limit, the stop signal), one request per connection (`Connection: close`), on at
// most max_connections threads (ConnectionThreads); the listening socket without
// SO_REUSEPORT (httplib's default would let a second server share the port) and with a
// listen backlog of max_connections.
#include <httplib.h>

#include <string>

#include "connection_stream.hpp"

namespace robodiff::server {

class LimitedServer final : public httplib::Server {
 public:
  LimitedServer(const ConnectionLimits& limits, std::size_t max_connections);
  ~LimitedServer() override;

  // Binds and listens on an IPv4 address (port 0: an ephemeral one); the bound port, or
  // -1 with errno set when it cannot.
  int bindTo(const std::string& host, int port);
  // Ends every connection's waits and stops the accept loop (listen_after_bind returns).
  void stopAll();

  // Why the current thread's connection stopped reading early (the error handler names
  // it in a 400); empty when it did not.
  static std::string currentProblem();

 private:
  bool process_and_close_socket(socket_t sock) override;

  ConnectionLimits limits_;
  std::size_t max_connections_;
  int stop_fd_;  // an eventfd, readable once stopping
};

}  // namespace robodiff::server
