// The HTTP server: robodiff's routes and checks on cpp-httplib. Every request goes through
// one pre-routing handler (answer()): target, Host (host_check.hpp), path, method, then
// the route; httplib parses, writes and owns the accept loop (limited_server.hpp adds the
// limits). The error handler gives httplib's own refusals (400) a body that says why.
#include "robodiff/server/http_server.hpp"

#include <arpa/inet.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "host_check.hpp"
#include "limited_server.hpp"

namespace robodiff::server {
namespace {

using Handled = httplib::Server::HandlerResponse;

// This machine's hostname (gethostname), which browsers on the LAN may use.
std::string machineName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "localhost";
  return name;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

Handled plain(httplib::Response& res, int status, const std::string& text) {
  res.status = status;
  res.set_content(text + "\n", "text/plain; charset=utf-8");
  return Handled::Handled;
}

// httplib's request as the routes see it (without the REMOTE_ADDR, ... it adds).
HttpRequest toRequest(const httplib::Request& req) {
  HttpRequest r;
  r.method = req.method;
  r.target = req.target;
  r.path = req.path;
  const std::size_t q = req.target.find('?');
  r.query = q == std::string::npos ? "" : req.target.substr(q + 1);
  for (const auto& [name, value] : req.headers)
    if (name != "REMOTE_ADDR" && name != "REMOTE_PORT" && name != "LOCAL_ADDR" && name != "LOCAL_PORT")
      r.headers.emplace_back(lower(name), value);
  return r;
}

// Blocks the signals a process handles (SIGCHLD, SIGUSR1, ...) on the calling thread and
// the connection threads it starts: httplib 0.11 ends its accept loop on an accept()
// interrupted by a signal (EINTR), which would close the listener for good. Faults
// (SIGSEGV, ...) stay unblocked.
void blockAsyncSignals() {
  sigset_t set;
  ::sigfillset(&set);
  for (const int fault : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP}) ::sigdelset(&set, fault);
  ::pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

void fill(httplib::Response& res, const HttpResponse& out) {
  res.status = out.status;
  for (const auto& [name, value] : out.headers) res.set_header(name, value);
  res.set_content(out.body, out.content_type);
}

}  // namespace

struct HttpServer::Impl {
  HttpServerOptions options;
  std::vector<std::string> host_names;  // options.allowed_hosts and this machine's name
  std::map<std::string, HttpHandler, std::less<>> routes;
  mutable std::mutex route_mutex;  // routes run one at a time, as they always have
  LimitedServer server;
  std::thread thread;  // httplib's accept loop
  std::atomic<bool> loop_ended{false};
  bool started = false;
  std::uint16_t bound_port = 0;

  explicit Impl(HttpServerOptions o)
      : options(std::move(o)),
        host_names(options.allowed_hosts),
        server({options.max_head_bytes, options.read_timeout, options.write_timeout}, options.max_connections) {
    host_names.push_back(machineName());
    server.set_pre_routing_handler(
        [this](const httplib::Request& req, httplib::Response& res) { return answer(req, res); });
    server.set_error_handler([](const httplib::Request&, httplib::Response& res) { explainError(res); });
    server.set_post_routing_handler([](const httplib::Request&, httplib::Response& res) {
      if (!res.has_header("Cache-Control")) res.set_header("Cache-Control", "no-store");
    });
  }

  // A refusal naming the host a request asked for, or nullopt when the Host is ours.
  std::optional<std::string> misdirected(const httplib::Request& req) const {
    const std::size_t count = req.get_header_value_count("Host");
    if (count == 0 && req.version == "HTTP/1.1")  // an empty Host is left out by httplib
      return "misdirected request: an HTTP/1.1 request must name its Host";
    for (std::size_t i = 0; i < count; ++i) {
      const std::string value = req.get_header_value("Host", i);
      if (!hostAllowed(value, host_names))
        return "misdirected request: this server does not answer to host '" + value.substr(0, 200) +
               "' (it answers to IP addresses, localhost, " + machineName() +
               " and http.allowed_hosts in robodiffd.conf)";
    }
    return std::nullopt;
  }

  // Every request: checked, then answered by its route.
  Handled answer(const httplib::Request& req, httplib::Response& res) const {
    if (req.target.empty() || req.target.front() != '/')
      return plain(res, 400, "bad request: request target must start with '/'");
    if (const auto why = misdirected(req)) return plain(res, 421, *why);
    const auto route = routes.find(req.path);
    if (route == routes.end()) return plain(res, 404, "not found: " + req.path);
    if (req.method != "GET" && req.method != "HEAD") {
      plain(res, 405, "method " + req.method + " not allowed on " + req.path + " (GET, HEAD)");
      res.set_header("Allow", "GET, HEAD");
      return Handled::Handled;
    }
    try {
      std::lock_guard one_at_a_time(route_mutex);
      fill(res, route->second(toRequest(req)));
    } catch (const std::exception& e) {
      return plain(res, 500, std::string("internal error: ") + e.what());
    }
    return Handled::Handled;
  }

  // httplib's own refusals come without a body: say why.
  static void explainError(httplib::Response& res) {
    if (!res.body.empty()) return;
    if (res.status != 400) {
      plain(res, res.status, "request refused (HTTP " + std::to_string(res.status) + ")");
      return;
    }
    const std::string problem = LimitedServer::currentProblem();
    plain(res, 400, "bad request: " + (problem.empty() ? std::string("malformed request line or header (expected "
                                                                     "'METHOD /path HTTP/1.1' and CRLF line ends)")
                                                       : problem));
  }
};

HttpServer::HttpServer(HttpServerOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}

HttpServer::~HttpServer() { stop(); }

void HttpServer::route(std::string path, HttpHandler handler) { impl_->routes[std::move(path)] = std::move(handler); }

void HttpServer::start() {
  Impl& s = *impl_;
  if (s.started) throw std::runtime_error("HTTP server already started");
  const std::string where = s.options.host + ":" + std::to_string(s.options.port);
  unsigned char ipv4[4];
  if (::inet_pton(AF_INET, s.options.host.c_str(), ipv4) != 1)
    throw std::runtime_error("HTTP listen address " + where + ": '" + s.options.host + "' is not an IPv4 address");
  const int port = s.server.bindTo(s.options.host, s.options.port);
  if (port <= 0) {
    const int error = errno;
    throw std::runtime_error("HTTP listen address " + where + ": " +
                             (error != 0 ? std::strerror(error) : "cannot bind and listen"));
  }
  s.started = true;
  s.bound_port = static_cast<std::uint16_t>(port);
  s.thread = std::thread([&s] {
    blockAsyncSignals();
    s.server.listen_after_bind();
    s.loop_ended = true;
  });
  // httplib's stop() only acts on a running loop: wait until it runs.
  while (!s.server.is_running() && !s.loop_ended) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

void HttpServer::stop() {
  Impl& s = *impl_;
  if (!s.thread.joinable()) return;
  s.server.stopAll();
  s.thread.join();
}

std::uint16_t HttpServer::port() const { return impl_->bound_port; }

std::string HttpServer::address() const { return impl_->options.host + ":" + std::to_string(impl_->bound_port); }

}  // namespace robodiff::server
