// A minimal W3C WebDriver client for browser tests: chromedriver as a child process
// (ChromeDriverProcess) and one headless Chromium session driven through it
// (WebDriverSession), over a keep-alive HTTP/1.1 connection of its own (HttpConnection).
//
//   ChromeDriverProcess driver(dir / "chromedriver.log");
//   if (!driver.available()) GTEST_SKIP() << driver.unavailableReason();
//   WebDriverSession browser(driver);
//   browser.navigate("http://127.0.0.1:9464/");
//   EXPECT_TRUE(browser.waitFor("document.querySelector('#x') !== null", 5s));
//
// WebDriver errors throw std::runtime_error naming the command and WebDriver's error and
// message.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/temp_dir.hpp"

namespace robodiff::testing {

// Standard base64 (RFC 4648) to bytes; whitespace is skipped, anything else not in the
// alphabet throws std::runtime_error.
std::vector<std::uint8_t> base64Decode(std::string_view text);

// True when `bytes` starts with the PNG signature.
bool isPng(const std::vector<std::uint8_t>& bytes);

struct HttpResponse {
  int status = 0;
  std::string body;
};

// One keep-alive HTTP/1.1 connection to 127.0.0.1:port, (re)connected on demand. Replies
// are read by Content-Length (or chunked), never by waiting for the server to close.
class HttpConnection {
 public:
  explicit HttpConnection(std::uint16_t port) : port_(port) {}
  ~HttpConnection();
  HttpConnection(const HttpConnection&) = delete;
  HttpConnection& operator=(const HttpConnection&) = delete;

  // Sends `method path` with `body` as application/json (none when empty) and reads the
  // reply. Throws std::runtime_error when there is no reply within `timeout`.
  HttpResponse request(const std::string& method, const std::string& path, const std::string& body = "",
                       std::chrono::milliseconds timeout = std::chrono::seconds(60));

 private:
  void connect();
  void disconnect();

  std::uint16_t port_;
  int fd_ = -1;
  std::string pending_;  // bytes read past the last reply
};

// chromedriver running on a free port of 127.0.0.1, logging to `log_path`.
class ChromeDriverProcess {
 public:
  explicit ChromeDriverProcess(std::filesystem::path log_path,
                               std::chrono::milliseconds ready_timeout = std::chrono::seconds(20));
  ~ChromeDriverProcess() { stop(); }
  ChromeDriverProcess(const ChromeDriverProcess&) = delete;
  ChromeDriverProcess& operator=(const ChromeDriverProcess&) = delete;

  // Whether both programs were found; when not, unavailableReason() names the missing one.
  bool available() const { return unavailable_reason_.empty(); }
  const std::string& unavailableReason() const { return unavailable_reason_; }
  // Whether chromedriver answered /status ready; when not, startError() says why.
  bool running() const { return pid_ > 0; }
  const std::string& startError() const { return start_error_; }

  std::uint16_t port() const { return port_; }
  pid_t pid() const { return pid_; }
  const std::filesystem::path& chromiumPath() const { return chromium_; }
  std::string log() const;

  // SIGTERM, then SIGKILL (chromedriver and the browsers it left) after `timeout`; reaps.
  void stop(std::chrono::milliseconds timeout = std::chrono::seconds(5));

 private:
  bool startOn(std::uint16_t port, std::chrono::milliseconds ready_timeout);

  std::filesystem::path log_path_, chromedriver_, chromium_;
  std::string unavailable_reason_, start_error_;
  std::uint16_t port_ = 0;
  pid_t pid_ = -1;
};

// One headless Chromium session (1400 x 1500 window, fresh profile in a temporary directory); quit at
// destruction.
class WebDriverSession {
 public:
  explicit WebDriverSession(const ChromeDriverProcess& driver);
  ~WebDriverSession();
  WebDriverSession(const WebDriverSession&) = delete;
  WebDriverSession& operator=(const WebDriverSession&) = delete;

  const std::string& id() const { return session_id_; }

  void navigate(const std::string& url);
  // Runs `script` as a function body (use `return`), with `args` as arguments[...].
  nlohmann::json executeScript(const std::string& script, const nlohmann::json& args = nlohmann::json::array());
  // The viewport as PNG bytes.
  std::vector<std::uint8_t> screenshotPng();
  // Polls the JS expression `predicate` until it is `true`; on a timeout the failure
  // names the last value it had (or the last exception thrown evaluating it).
  ::testing::AssertionResult waitFor(const std::string& predicate, std::chrono::milliseconds timeout,
                                     std::chrono::milliseconds interval = std::chrono::milliseconds(100));
  // DELETE /session/{id}; no-op once done.
  void quit();

 private:
  // One WebDriver command; its "value", or throws naming error and message.
  nlohmann::json command(const std::string& method, const std::string& path, const nlohmann::json& body = nullptr,
                         std::chrono::milliseconds timeout = std::chrono::seconds(60));

  std::unique_ptr<TempDir> profile_;
  HttpConnection http_;
  std::string session_id_;
};

}  // namespace robodiff::testing
