#pragma once
// robodiffd's HTTP/1.1 server for operators' endpoints (metrics, probes, dashboard):
// cpp-httplib underneath (http_server.cpp, limited_server.hpp), a thread per connection
// up to max_connections, so a slow or silent client never holds up another. GET and HEAD
// only; one request per connection (`Connection: close`); the request head is limited in
// size and must arrive within the read timeout, else the client gets 400 or is dropped.
// Routes are exact paths (the query string is ignored) answered by callbacks, one at a
// time (a mutex), on the connections' threads: they must be quick.
//
// Answers: the route's response; 404 for an unknown path; 405 (with Allow) for another
// method on a known path; 400 for a malformed or oversized head (a method httplib does not
// know, a target not starting with '/', a version other than HTTP/1.0 and 1.1, a header
// line without ':'); 421 for a Host header that names another host, or an HTTP/1.1
// request without one (host_check.hpp); 500 when a route throws. Bodies are sent gzip- or
// brotli-compressed when the client asks (Accept-Encoding), as Debian builds httplib.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace robodiff::server {

struct HttpServerOptions {
  std::string host = "127.0.0.1";  // IPv4 address to bind (0.0.0.0: every interface)
  std::uint16_t port = 9464;       // 0: an ephemeral port (port() tells which)
  std::size_t max_head_bytes = 8192;                       // request line and headers
  std::chrono::milliseconds read_timeout = std::chrono::seconds(5);   // for the whole head
  std::chrono::milliseconds write_timeout = std::chrono::seconds(5);  // for the whole response
  std::size_t max_connections = 64;  // beyond: new connections wait in the listen backlog
  // Host header names accepted besides IP literals, localhost and this machine's hostname
  // (a request naming another host gets 421: DNS rebinding). A request without Host is
  // answered (HTTP/1.0 tools); browsers always send one.
  std::vector<std::string> allowed_hosts;
};

struct HttpRequest {
  std::string method;  // "GET" or "HEAD"
  std::string target;  // as sent: "/metrics?x=1"
  std::string path;    // without the query, %-decoded: "/metrics"
  std::string query;   // after '?', undecoded
  std::vector<std::pair<std::string, std::string>> headers;  // names lower-cased, empty values left out
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;  // extra ones
};

using HttpHandler = std::function<HttpResponse(const HttpRequest&)>;

class HttpServer {
 public:
  explicit HttpServer(HttpServerOptions options = {});
  ~HttpServer();  // stop()
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Answers GET and HEAD on `path` (exact match). Before start().
  void route(std::string path, HttpHandler handler);

  // Binds, listens and starts the accept thread. Throws std::runtime_error naming the address and
  // the reason (address in use, not an IPv4 address, ...). Once only.
  void start();
  // Closes the listener and every connection, and joins the threads. Idempotent.
  void stop();

  std::uint16_t port() const;   // the bound port (after start)
  std::string address() const;  // "host:port" as bound (after start)

 private:
  struct Impl;  // http_server.cpp
  std::unique_ptr<Impl> impl_;
};

}  // namespace robodiff::server
