#include "support/webdriver.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace robodiff::testing {

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

std::string lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A port of 127.0.0.1 nobody listens on right now (bound to 0, read back, released).
std::uint16_t freeLoopbackPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = 0;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof a;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &length) != 0) {
    const std::string error = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error("binding a free port: " + error);
  }
  ::close(fd);
  return ntohs(a.sin_port);
}

// `environment_variable` if set, else `fallback`; empty when that is not executable.
std::filesystem::path findProgram(const char* environment_variable, const char* fallback, std::string& looked_at) {
  const char* from_environment = std::getenv(environment_variable);
  const std::string path = (from_environment != nullptr && *from_environment != '\0') ? from_environment : fallback;
  looked_at = path;
  return ::access(path.c_str(), X_OK) == 0 ? std::filesystem::path(path) : std::filesystem::path();
}

std::string tail(const std::string& text, std::size_t n = 4000) {
  return text.size() <= n ? text : "..." + text.substr(text.size() - n);
}

}  // namespace

// ---- base64 ----------------------------------------------------------------------------

std::vector<std::uint8_t> base64Decode(std::string_view text) {
  auto sextet = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::vector<std::uint8_t> out;
  out.reserve(text.size() / 4 * 3);
  std::uint32_t bits = 0;
  int bit_count = 0;
  bool padding = false;
  for (const char c : text) {
    if (std::isspace(static_cast<unsigned char>(c))) continue;
    if (c == '=') {
      padding = true;
      continue;
    }
    const int value = sextet(c);
    if (value < 0 || padding) throw std::runtime_error(std::string("base64: unexpected character '") + c + "'");
    bits = (bits << 6) | static_cast<std::uint32_t>(value);
    bit_count += 6;
    if (bit_count >= 8) {
      bit_count -= 8;
      out.push_back(static_cast<std::uint8_t>((bits >> bit_count) & 0xFF));
    }
  }
  return out;
}

bool isPng(const std::vector<std::uint8_t>& bytes) {
  static const std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  return bytes.size() >= 8 && std::equal(kSignature, kSignature + 8, bytes.begin());
}

// ---- HttpConnection ----------------------------------------------------------------------

HttpConnection::~HttpConnection() { disconnect(); }

void HttpConnection::connect() {
  disconnect();
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port_);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    const std::string error = std::strerror(errno);
    disconnect();
    throw std::runtime_error("connecting to 127.0.0.1:" + std::to_string(port_) + ": " + error);
  }
}

void HttpConnection::disconnect() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  pending_.clear();
}

HttpResponse HttpConnection::request(const std::string& method, const std::string& path, const std::string& body,
                                     milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  std::string raw = method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port_) +
                    "\r\nAccept: application/json\r\nConnection: keep-alive\r\n";
  if (!body.empty()) raw += "Content-Type: application/json; charset=utf-8\r\n";
  raw += "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body;

  // Reads more into pending_; false when the peer closed. Throws on a timeout.
  auto fill = [&]() -> bool {
    const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now()).count();
    pollfd p{fd_, POLLIN, 0};
    if (left <= 0 || ::poll(&p, 1, static_cast<int>(left)) <= 0) {
      disconnect();
      throw std::runtime_error(method + " " + path + ": no reply within " + std::to_string(timeout.count()) + " ms");
    }
    char buffer[16384];
    const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
    if (n <= 0) return false;
    pending_.append(buffer, static_cast<std::size_t>(n));
    return true;
  };

  // A kept-alive connection the server has closed meanwhile fails on first use with
  // nothing read back: then once more on a fresh one.
  for (int attempt = 0;; ++attempt) {
    const bool reused = fd_ >= 0;
    if (!reused) connect();
    pending_.clear();
    std::size_t sent = 0;
    bool failed = false;
    while (sent < raw.size() && !failed) {
      const ssize_t n = ::send(fd_, raw.data() + sent, raw.size() - sent, MSG_NOSIGNAL);
      if (n <= 0) failed = true;
      else sent += static_cast<std::size_t>(n);
    }
    std::size_t head_end = std::string::npos;
    while (!failed && (head_end = pending_.find("\r\n\r\n")) == std::string::npos)
      if (!fill()) failed = true;
    if (failed) {
      const bool nothing_came = pending_.empty();
      disconnect();
      if (reused && nothing_came && attempt == 0) continue;
      throw std::runtime_error(method + " " + path + ": connection to 127.0.0.1:" + std::to_string(port_) +
                               " closed without a complete reply");
    }

    HttpResponse response;
    const std::string head = pending_.substr(0, head_end + 2);
    if (head.rfind("HTTP/1.", 0) != 0 || head.size() < 12) {
      disconnect();
      throw std::runtime_error(method + " " + path + ": not an HTTP reply: " + tail(head, 200));
    }
    response.status = std::atoi(head.c_str() + 9);
    const std::string lower_head = lowercase(head);
    auto header = [&](const std::string& name) -> std::string {
      const auto at = lower_head.find("\r\n" + name + ":");
      if (at == std::string::npos) return "";
      const auto begin = lower_head.find_first_not_of(' ', at + 3 + name.size());
      return lower_head.substr(begin, lower_head.find("\r\n", begin) - begin);
    };
    pending_.erase(0, head_end + 4);

    const std::string length = header("content-length");
    if (!length.empty()) {
      const std::size_t n = std::stoul(length);
      while (pending_.size() < n)
        if (!fill()) throw std::runtime_error(method + " " + path + ": reply body cut short");
      response.body = pending_.substr(0, n);
      pending_.erase(0, n);
    } else if (header("transfer-encoding").find("chunked") != std::string::npos) {
      while (true) {
        std::size_t line_end;
        while ((line_end = pending_.find("\r\n")) == std::string::npos)
          if (!fill()) throw std::runtime_error(method + " " + path + ": chunked reply cut short");
        const std::size_t chunk = std::stoul(pending_.substr(0, line_end), nullptr, 16);
        if (chunk == 0) {  // the last chunk, then trailers up to an empty line
          std::size_t end;
          while ((end = pending_.find("\r\n\r\n", line_end)) == std::string::npos)
            if (!fill()) throw std::runtime_error(method + " " + path + ": chunked reply cut short");
          pending_.erase(0, end + 4);
          break;
        }
        while (pending_.size() < line_end + 2 + chunk + 2)
          if (!fill()) throw std::runtime_error(method + " " + path + ": chunked reply cut short");
        response.body += pending_.substr(line_end + 2, chunk);
        pending_.erase(0, line_end + 2 + chunk + 2);
      }
    } else {  // neither: the body runs until the server closes
      while (fill()) {
      }
      response.body = pending_;
      disconnect();
    }
    if (header("connection") == "close") disconnect();
    return response;
  }
}

// ---- ChromeDriverProcess ------------------------------------------------------------------

ChromeDriverProcess::ChromeDriverProcess(std::filesystem::path log_path, milliseconds ready_timeout)
    : log_path_(std::move(log_path)) {
  std::string looked_at;
  chromedriver_ = findProgram("CHROMEDRIVER", "/usr/bin/chromedriver", looked_at);
  if (chromedriver_.empty()) {
    unavailable_reason_ = "chromedriver not found (no executable " + looked_at +
                          "; $CHROMEDRIVER names another): deploy/install-deps.sh installs it (chromium-driver)";
    return;
  }
  chromium_ = findProgram("CHROMIUM", "/usr/bin/chromium", looked_at);
  if (chromium_.empty()) {
    unavailable_reason_ = "chromium not found (no executable " + looked_at +
                          "; $CHROMIUM names another): deploy/install-deps.sh installs it (chromium)";
    return;
  }
  // The free port may be taken between finding and binding it: a few tries.
  for (int attempt = 0; attempt < 3 && !running(); ++attempt) startOn(freeLoopbackPort(), ready_timeout);
}

bool ChromeDriverProcess::startOn(std::uint16_t port, milliseconds ready_timeout) {
  const std::string port_flag = "--port=" + std::to_string(port);
  const std::string log_flag = "--log-path=" + log_path_.string();
  const pid_t pid = ::fork();
  if (pid < 0) {
    start_error_ = std::string("fork: ") + std::strerror(errno);
    return false;
  }
  if (pid == 0) {
    ::setpgid(0, 0);                    // its browsers in its group, to clean up after a crash
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);  // and gone with the test process
    signal(SIGTERM, SIG_DFL);           // the test process may ignore it; exec keeps that
    sigset_t none;
    ::sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    const int null_fd = ::open("/dev/null", O_RDONLY);
    if (null_fd >= 0) ::dup2(null_fd, STDIN_FILENO);
    const int log_fd = ::open(log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (log_fd >= 0) {
      ::dup2(log_fd, STDOUT_FILENO);
      ::dup2(log_fd, STDERR_FILENO);
    }
    ::execl(chromedriver_.c_str(), chromedriver_.c_str(), port_flag.c_str(), log_flag.c_str(), "--append-log",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // as the child does, whichever runs first
  pid_ = pid;
  port_ = port;
  const auto deadline = Clock::now() + ready_timeout;
  HttpConnection http(port);
  std::string last;
  while (Clock::now() < deadline) {
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      const std::string how = WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                                : "signal " + std::to_string(WTERMSIG(status));
      start_error_ = "chromedriver exited before it was ready (" + how + "); log:\n" + tail(log());
      return false;
    }
    try {
      const HttpResponse r = http.request("GET", "/status", "", std::chrono::seconds(2));
      last = r.body;
      if (r.status == 200 && nlohmann::json::parse(r.body).at("value").value("ready", false)) return true;
    } catch (const std::exception& e) {
      last = e.what();
    }
    std::this_thread::sleep_for(milliseconds(50));
  }
  stop();
  start_error_ = "chromedriver not ready on port " + std::to_string(port) + " within " +
                 std::to_string(ready_timeout.count()) + " ms (last /status: " + last + "); log:\n" + tail(log());
  return false;
}

std::string ChromeDriverProcess::log() const {
  std::ifstream in(log_path_);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void ChromeDriverProcess::stop(milliseconds timeout) {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGTERM);
  const auto deadline = Clock::now() + timeout;
  siginfo_t info{};
  bool exited = false;
  while (Clock::now() < deadline) {
    info.si_pid = 0;  // exited but not reaped yet: its PID (= its group's id) stays ours
    if (::waitid(P_PID, static_cast<id_t>(pid_), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == pid_) {
      exited = true;
      break;
    }
    std::this_thread::sleep_for(milliseconds(20));
  }
  if (!exited) ::kill(pid_, SIGKILL);
  ::kill(-pid_, SIGKILL);  // browsers it left behind in its process group
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
}

// ---- WebDriverSession ---------------------------------------------------------------------

WebDriverSession::WebDriverSession(const ChromeDriverProcess& driver)
    : profile_(std::make_unique<TempDir>()), http_(driver.port()) {
  if (!driver.running()) throw std::runtime_error("chromedriver is not running: " + driver.startError());
  const nlohmann::json options = {
      {"binary", driver.chromiumPath().string()},
      {"args",
       {"--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1400,1500",
        "--user-data-dir=" + profile_->path().string()}}};
  const nlohmann::json capabilities = {{"capabilities", {{"alwaysMatch", {{"goog:chromeOptions", options}}}}}};
  const nlohmann::json value = command("POST", "/session", capabilities, std::chrono::seconds(60));
  session_id_ = value.at("sessionId").get<std::string>();
}

WebDriverSession::~WebDriverSession() {
  try {
    quit();
  } catch (const std::exception&) {  // chromedriver gone already: nothing left to quit
  }
}

void WebDriverSession::quit() {
  if (session_id_.empty()) return;
  const std::string id = session_id_;
  session_id_.clear();
  command("DELETE", "/session/" + id, nullptr, std::chrono::seconds(20));
}

nlohmann::json WebDriverSession::command(const std::string& method, const std::string& path,
                                         const nlohmann::json& body, milliseconds timeout) {
  std::string payload;
  if (!body.is_null()) payload = body.dump();
  else if (method == "POST") payload = "{}";  // WebDriver wants a JSON object on every POST
  const HttpResponse r = http_.request(method, path, payload, timeout);
  nlohmann::json reply;
  try {
    reply = nlohmann::json::parse(r.body);
  } catch (const std::exception&) {
    throw std::runtime_error("WebDriver " + method + " " + path + ": HTTP " + std::to_string(r.status) +
                             ", not JSON: " + tail(r.body, 500));
  }
  const nlohmann::json value = reply.is_object() && reply.contains("value") ? reply["value"] : nlohmann::json();
  if (r.status != 200 || (value.is_object() && value.contains("error"))) {
    const std::string error = value.is_object() ? value.value("error", "") : "";
    const std::string message = value.is_object() ? value.value("message", "") : tail(r.body, 500);
    throw std::runtime_error("WebDriver " + method + " " + path + ": HTTP " + std::to_string(r.status) + " " + error +
                             ": " + message);
  }
  return value;
}

void WebDriverSession::navigate(const std::string& url) {
  command("POST", "/session/" + session_id_ + "/url", {{"url", url}});
}

nlohmann::json WebDriverSession::executeScript(const std::string& script, const nlohmann::json& args) {
  return command("POST", "/session/" + session_id_ + "/execute/sync", {{"script", script}, {"args", args}});
}

std::vector<std::uint8_t> WebDriverSession::screenshotPng() {
  return base64Decode(command("GET", "/session/" + session_id_ + "/screenshot").get<std::string>());
}

::testing::AssertionResult WebDriverSession::waitFor(const std::string& predicate, milliseconds timeout,
                                                     milliseconds interval) {
  const auto deadline = Clock::now() + timeout;
  std::string last;
  while (true) {
    try {
      const nlohmann::json value = executeScript("return (" + predicate + "\n);");
      if (value == true) return ::testing::AssertionSuccess();
      last = value.dump();
    } catch (const std::exception& e) {
      last = std::string("threw: ") + e.what();
    }
    if (Clock::now() >= deadline) break;
    std::this_thread::sleep_for(interval);
  }
  return ::testing::AssertionFailure() << "not true within " << timeout.count() << " ms: " << predicate
                                       << "\n  last value: " << last;
}

}  // namespace robodiff::testing
