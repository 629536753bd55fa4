// The HTTP server: a poll() loop over the listener, a wake-up pipe and the connections.
// Each connection reads its head (non-blocking, bounded, timed), is answered by a route,
// writes its response, then half-closes and drains the client's leftovers briefly before
// closing (closing with unread input would reset the connection and lose the response).
#include "robodiff/server/http_server.hpp"

#include "host_check.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string_view>
#include <thread>

namespace robodiff::server {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::chrono::milliseconds kLinger{500};  // draining the client after the response

// This machine's hostname (gethostname), which browsers on the LAN may use.
std::string machineName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "localhost";
  return name;
}

void setNonBlocking(int fd) { ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL, 0) | O_NONBLOCK); }

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return std::string(s);
}

// The end of the head ("\r\n\r\n", or "\n\n" from lenient clients), npos when incomplete.
std::size_t headEnd(const std::string& in) {
  const std::size_t crlf = in.find("\r\n\r\n");
  const std::size_t lf = in.find("\n\n");
  if (crlf == std::string::npos && lf == std::string::npos) return std::string::npos;
  if (crlf != std::string::npos && (lf == std::string::npos || crlf + 2 < lf)) return crlf + 4;
  return lf + 2;
}

// Parses a request head; false (and why) when it is malformed.
bool parseHead(std::string_view head, HttpRequest& request, std::string& why) {
  std::vector<std::string_view> lines;
  while (!head.empty()) {
    const std::size_t nl = head.find('\n');
    std::string_view line = head.substr(0, nl);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    if (nl == std::string_view::npos) break;
    head.remove_prefix(nl + 1);
  }
  if (lines.empty() || lines[0].empty()) return why = "empty request line", false;
  const std::string_view first = lines[0];
  const std::size_t sp1 = first.find(' ');
  const std::size_t sp2 = sp1 == std::string_view::npos ? sp1 : first.find(' ', sp1 + 1);
  if (sp2 == std::string_view::npos || first.find(' ', sp2 + 1) != std::string_view::npos)
    return why = "request line is not 'METHOD TARGET HTTP/1.x'", false;
  request.method = std::string(first.substr(0, sp1));
  request.target = std::string(first.substr(sp1 + 1, sp2 - sp1 - 1));
  const std::string_view version = first.substr(sp2 + 1);
  if (version != "HTTP/1.1" && version != "HTTP/1.0")
    return why = "unsupported version '" + std::string(version) + "'", false;
  if (request.method.empty() || request.target.empty() || request.target.front() != '/')
    return why = "request target must start with '/'", false;
  for (const char c : request.method)
    if (!std::isupper(static_cast<unsigned char>(c))) return why = "malformed method", false;
  const std::size_t q = request.target.find('?');
  request.path = request.target.substr(0, q);
  request.query = q == std::string::npos ? "" : request.target.substr(q + 1);
  for (std::size_t i = 1; i < lines.size(); ++i) {
    if (lines[i].empty()) continue;
    const std::size_t colon = lines[i].find(':');
    if (colon == std::string_view::npos || colon == 0) return why = "malformed header line", false;
    request.headers.emplace_back(lower(std::string(lines[i].substr(0, colon))), trim(lines[i].substr(colon + 1)));
  }
  return true;
}

std::string serialize(const HttpResponse& r, bool head_only) {
  std::string out = "HTTP/1.1 " + std::to_string(r.status) + " " + httpReasonPhrase(r.status) + "\r\n";
  out += "Content-Type: " + r.content_type + "\r\n";
  out += "Content-Length: " + std::to_string(r.body.size()) + "\r\n";
  out += "Connection: close\r\n";
  out += "Cache-Control: no-store\r\n";
  for (const auto& [name, value] : r.headers) out += name + ": " + value + "\r\n";
  out += "\r\n";
  if (!head_only) out += r.body;
  return out;
}

HttpResponse plain(int status, std::string body) {
  HttpResponse r;
  r.status = status;
  r.body = std::move(body) + "\n";
  return r;
}

}  // namespace

const char* httpReasonPhrase(int status) {
  switch (status) {
    case 200: return "OK";
    case 400: return "Bad Request";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 421: return "Misdirected Request";
    case 500: return "Internal Server Error";
    case 503: return "Service Unavailable";
  }
  return "Unknown";
}

struct HttpServer::Impl {
  struct Connection {
    int fd = -1;
    enum class Phase { Reading, Writing, Draining } phase = Phase::Reading;
    std::string in, out;
    std::size_t written = 0;
    Clock::time_point deadline;
  };

  HttpServerOptions options;
  std::vector<std::string> host_names;  // options.allowed_hosts and this machine's name
  std::map<std::string, HttpHandler, std::less<>> routes;
  int listener = -1;
  int wake[2] = {-1, -1};  // stop() writes to wake[1]
  std::uint16_t bound_port = 0;
  std::thread thread;
  std::atomic<bool> stopping{false};
  std::vector<Connection> connections;

  HttpResponse answer(const std::string& head) {
    HttpRequest request;
    std::string why;
    if (!parseHead(head, request, why)) return plain(400, "bad request: " + why);
    for (const auto& [name, value] : request.headers)
      if (name == "host" && !hostAllowed(value, host_names))
        return plain(421, "misdirected request: this server does not answer to host '" + value.substr(0, 200) +
                              "' (it answers to IP addresses, localhost, " + machineName() +
                              " and http.allowed_hosts in robodiffd.conf)");
    const auto route = routes.find(request.path);
    if (route == routes.end()) return plain(404, "not found: " + request.path);
    if (request.method != "GET" && request.method != "HEAD") {
      HttpResponse r = plain(405, "method " + request.method + " not allowed on " + request.path + " (GET, HEAD)");
      r.headers.emplace_back("Allow", "GET, HEAD");
      return r;
    }
    try {
      return route->second(request);
    } catch (const std::exception& e) {
      return plain(500, std::string("internal error: ") + e.what());
    }
  }

  static bool isHead(const std::string& in) { return in.rfind("HEAD ", 0) == 0; }

  void respond(Connection& c, const HttpResponse& response, bool head_only) {
    c.out = serialize(response, head_only);
    c.written = 0;
    c.phase = Connection::Phase::Writing;
    c.deadline = Clock::now() + options.write_timeout;
  }

  // Reads what is there; false when the connection is to be closed.
  bool onReadable(Connection& c) {
    char buffer[4096];
    for (;;) {
      const ssize_t n = ::recv(c.fd, buffer, sizeof buffer, 0);
      if (n > 0) {
        if (c.phase == Connection::Phase::Draining) continue;  // discarded
        c.in.append(buffer, static_cast<std::size_t>(n));
        if (const std::size_t end = headEnd(c.in); end != std::string::npos && end <= options.max_head_bytes) {
          const std::string head = c.in.substr(0, end);
          respond(c, answer(head), isHead(head));
          return onWritable(c);
        }
        if (c.in.size() > options.max_head_bytes) {
          respond(c, plain(400, "bad request: request head over " + std::to_string(options.max_head_bytes) + " bytes"),
                  false);
          return onWritable(c);
        }
        continue;
      }
      if (n == 0) return false;  // the client closed (or finished draining)
      if (errno == EINTR) continue;
      return errno == EAGAIN || errno == EWOULDBLOCK;
    }
  }

  bool onWritable(Connection& c) {
    while (c.written < c.out.size()) {
      const ssize_t n = ::send(c.fd, c.out.data() + c.written, c.out.size() - c.written, MSG_NOSIGNAL);
      if (n > 0) {
        c.written += static_cast<std::size_t>(n);
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
      return false;
    }
    ::shutdown(c.fd, SHUT_WR);
    c.phase = Connection::Phase::Draining;
    c.deadline = Clock::now() + kLinger;
    return true;
  }

  void acceptAll() {
    while (connections.size() < options.max_connections) {
      const int fd = ::accept4(listener, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) return;  // EAGAIN, or a connection that went away meanwhile
      Connection c;
      c.fd = fd;
      c.deadline = Clock::now() + options.read_timeout;
      connections.push_back(std::move(c));
    }
  }

  void loop() {
    std::vector<pollfd> fds;
    while (!stopping.load()) {
      fds.clear();
      fds.push_back({wake[0], POLLIN, 0});
      const bool accepting = connections.size() < options.max_connections;
      fds.push_back({accepting ? listener : -1, POLLIN, 0});
      auto next = Clock::now() + std::chrono::seconds(60);
      for (const Connection& c : connections) {
        fds.push_back({c.fd, static_cast<short>(c.phase == Connection::Phase::Writing ? POLLOUT : POLLIN), 0});
        next = std::min(next, c.deadline);
      }
      const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next - Clock::now()).count();
      const int ready = ::poll(fds.data(), fds.size(), static_cast<int>(std::clamp<long long>(wait + 1, 0, 60000)));
      if (ready < 0 && errno != EINTR) break;
      if (stopping.load()) break;
      const auto now = Clock::now();
      std::vector<Connection> kept;
      for (std::size_t i = 0; i < connections.size(); ++i) {
        Connection& c = connections[i];
        const short events = fds[i + 2].revents;
        bool keep = true;
        if (events & (POLLERR | POLLNVAL)) keep = false;
        else if (c.phase == Connection::Phase::Writing && (events & (POLLOUT | POLLHUP))) keep = onWritable(c);
        else if (c.phase != Connection::Phase::Writing && (events & (POLLIN | POLLHUP))) keep = onReadable(c);
        if (keep && now >= c.deadline) keep = false;  // too slow: reading, writing, or done draining
        if (keep) kept.push_back(std::move(c));
        else ::close(c.fd);
      }
      connections = std::move(kept);
      if (accepting && (fds[1].revents & POLLIN)) acceptAll();
    }
    for (Connection& c : connections) ::close(c.fd);
    connections.clear();
  }
};

HttpServer::HttpServer(HttpServerOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = std::move(options);
  impl_->host_names = impl_->options.allowed_hosts;
  impl_->host_names.push_back(machineName());
}

HttpServer::~HttpServer() { stop(); }

void HttpServer::route(std::string path, HttpHandler handler) { impl_->routes[std::move(path)] = std::move(handler); }

void HttpServer::start() {
  Impl& s = *impl_;
  if (s.listener >= 0) throw std::runtime_error("HTTP server already started");
  const std::string where = s.options.host + ":" + std::to_string(s.options.port);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(s.options.port);
  if (::inet_pton(AF_INET, s.options.host.c_str(), &address.sin_addr) != 1)
    throw std::runtime_error("HTTP listen address " + where + ": '" + s.options.host + "' is not an IPv4 address");
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("HTTP listen address " + where + ": socket: " + std::strerror(errno));
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0 || ::listen(fd, 64) != 0) {
    const int error = errno;
    ::close(fd);
    throw std::runtime_error("HTTP listen address " + where + ": " + std::strerror(error));
  }
  socklen_t length = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  s.bound_port = ntohs(address.sin_port);
  if (::pipe2(s.wake, O_CLOEXEC | O_NONBLOCK) != 0) {
    ::close(fd);
    throw std::runtime_error(std::string("HTTP server: pipe: ") + std::strerror(errno));
  }
  s.listener = fd;
  setNonBlocking(fd);
  s.thread = std::thread([&s] { s.loop(); });
}

void HttpServer::stop() {
  Impl& s = *impl_;
  if (s.listener < 0) return;
  s.stopping = true;
  const char byte = 0;
  [[maybe_unused]] const ssize_t n = ::write(s.wake[1], &byte, 1);
  if (s.thread.joinable()) s.thread.join();
  ::close(s.listener);
  ::close(s.wake[0]);
  ::close(s.wake[1]);
  s.listener = s.wake[0] = s.wake[1] = -1;
}

std::uint16_t HttpServer::port() const { return impl_->bound_port; }

std::string HttpServer::address() const { return impl_->options.host + ":" + std::to_string(impl_->bound_port); }

}  // namespace robodiff::server
