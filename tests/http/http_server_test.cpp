// The HTTP server against real sockets: routes, 404, 405, HEAD, oversized and malformed
// heads, a silent client that must not hold up others (and is dropped at the read
// timeout), concurrent clients, ephemeral ports, bad addresses.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "http/http_client.hpp"
#include "robodiff/server/http_server.hpp"

namespace robodiff::testing {
namespace {

using server::HttpRequest;
using server::HttpResponse;
using server::HttpServer;
using server::HttpServerOptions;
using namespace std::chrono_literals;

class HttpServerTest : public ::testing::Test {
 protected:
  void start(HttpServerOptions options = {}) {
    options.port = 0;
    server_ = std::make_unique<HttpServer>(options);
    server_->route("/hello", [](const HttpRequest& r) {
      HttpResponse out;
      out.body = "hello " + r.query + "\n";
      return out;
    });
    server_->route("/unready", [](const HttpRequest&) {
      HttpResponse out;
      out.status = 503;
      out.body = "no\n";
      return out;
    });
    server_->route("/throws", [](const HttpRequest&) -> HttpResponse { throw std::runtime_error("boom"); });
    server_->start();
    port_ = server_->port();
    ASSERT_NE(port_, 0);
  }
  std::unique_ptr<HttpServer> server_;
  std::uint16_t port_ = 0;
};

TEST_F(HttpServerTest, AnswersARouteWithStatusLineTypeAndLength) {
  start();
  const HttpReply r = httpGet(port_, "/hello?who=me");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, "hello who=me\n");
  EXPECT_NE(r.head.find("HTTP/1.1 200 OK\r\n"), std::string::npos) << r.head;
  EXPECT_EQ(r.header("Content-Length"), std::to_string(r.body.size()));
  EXPECT_EQ(r.header("Content-Type"), "text/plain; charset=utf-8");
  EXPECT_EQ(r.header("Connection"), "close");
  EXPECT_EQ(server_->address(), "127.0.0.1:" + std::to_string(port_));
}

TEST_F(HttpServerTest, RouteStatusesAreSent) {
  start();
  const HttpReply r = httpGet(port_, "/unready");
  EXPECT_EQ(r.status, 503);
  EXPECT_NE(r.head.find("503 Service Unavailable"), std::string::npos);
  EXPECT_EQ(httpGet(port_, "/throws").status, 500);
}

TEST_F(HttpServerTest, UnknownPathIs404) {
  start();
  const HttpReply r = httpGet(port_, "/nothing");
  EXPECT_EQ(r.status, 404);
  EXPECT_NE(r.head.find("404 Not Found"), std::string::npos);
  EXPECT_NE(r.body.find("/nothing"), std::string::npos);
}

TEST_F(HttpServerTest, PostIs405WithAllow) {
  start();
  const HttpReply r =
      rawRequest(port_, "POST /hello HTTP/1.1\r\nHost: localhost\r\nContent-Length: 3\r\n\r\nabc");
  EXPECT_EQ(r.status, 405);
  EXPECT_EQ(r.header("Allow"), "GET, HEAD");
  EXPECT_EQ(httpGet(port_, "/hello", "DELETE").status, 405);
}

TEST_F(HttpServerTest, HeadHasTheHeadersAndNoBody) {
  start();
  const HttpReply get = httpGet(port_, "/hello");
  const HttpReply head = httpGet(port_, "/hello", "HEAD");
  EXPECT_EQ(head.status, 200);
  EXPECT_TRUE(head.body.empty()) << head.body;
  EXPECT_EQ(head.header("Content-Length"), get.header("Content-Length"));
}

// DNS rebinding: a page on evil.example whose name resolves to 127.0.0.1 makes the browser
// send "Host: evil.example"; only names this host answers to are served.
TEST_F(HttpServerTest, HostHeadersNamingOtherHostsAre421) {
  HttpServerOptions options;
  options.allowed_hosts = {"Robot1.lan"};
  start(options);
  auto withHost = [&](const std::string& host) {
    return rawRequest(port_, "GET /hello HTTP/1.1\r\nHost: " + host + "\r\n\r\n");
  };
  for (const char* host : {"evil.example", "evil.example:" , "127.0.0.1.evil.example", "localhost.evil.example",
                           "[::1", "", "robot2.lan"}) {
    const HttpReply r = withHost(host);
    EXPECT_EQ(r.status, 421) << host;
    EXPECT_EQ(r.body.find("hello"), std::string::npos) << host;
  }
  EXPECT_NE(withHost("evil.example").head.find("421 Misdirected Request"), std::string::npos);
  EXPECT_NE(withHost("evil.example").body.find("http.allowed_hosts"), std::string::npos);
  for (const std::string& host : std::vector<std::string>{"127.0.0.1", "127.0.0.1:" + std::to_string(port_), "localhost", "LOCALHOST:80",
                                 "localhost.", "[::1]:8080", "10.1.2.3", "robot1.lan", "ROBOT1.LAN:9464"}) {
    const HttpReply r = withHost(host);
    EXPECT_EQ(r.status, 200) << host;
    EXPECT_EQ(r.body, "hello \n") << host;
  }
  EXPECT_EQ(rawRequest(port_, "GET /hello HTTP/1.0\r\n\r\n").status, 200);  // no Host: HTTP/1.0 tools
}

TEST_F(HttpServerTest, MalformedHeadsAre400) {
  start();
  EXPECT_EQ(rawRequest(port_, "GARBAGE\r\n\r\n").status, 400);
  EXPECT_EQ(rawRequest(port_, "GET hello HTTP/1.1\r\n\r\n").status, 400);
  EXPECT_EQ(rawRequest(port_, "GET /hello HTTP/2.0\r\n\r\n").status, 400);
  EXPECT_EQ(rawRequest(port_, "GET /hello HTTP/1.1\r\nno colon here\r\n\r\n").status, 400);
  // Lenient line ends still work.
  EXPECT_EQ(rawRequest(port_, "GET /hello HTTP/1.0\n\n").status, 200);
}

TEST_F(HttpServerTest, HeadOverTheLimitIs400AndTheServerGoesOn) {
  HttpServerOptions options;
  options.max_head_bytes = 1024;
  start(options);
  const std::string big = "GET /hello HTTP/1.1\r\nX-Padding: " + std::string(4000, 'a') + "\r\n\r\n";
  const HttpReply r = rawRequest(port_, big);
  EXPECT_EQ(r.status, 400);
  EXPECT_NE(r.body.find("1024"), std::string::npos) << r.body;
  // A head that never ends counts too.
  EXPECT_EQ(rawRequest(port_, "GET /hello HTTP/1.1\r\nX: " + std::string(2000, 'b')).status, 400);
  EXPECT_EQ(httpGet(port_, "/hello").status, 200);
}

TEST_F(HttpServerTest, SilentClientDoesNotBlockOthersAndIsDroppedAtTheTimeout) {
  HttpServerOptions options;
  options.read_timeout = 300ms;
  start(options);
  const int silent = connectLocal(port_);
  ASSERT_GE(silent, 0);
  const int partial = connectLocal(port_);  // sends half a head, then nothing
  ASSERT_GE(partial, 0);
  ::send(partial, "GET /hel", 8, MSG_NOSIGNAL);

  const auto before = std::chrono::steady_clock::now();
  EXPECT_EQ(httpGet(port_, "/hello").status, 200);
  EXPECT_LT(std::chrono::steady_clock::now() - before, 250ms);  // not after the silent ones' timeout

  // Both are closed by the server at the read timeout, without a response.
  const auto waited = std::chrono::steady_clock::now();
  EXPECT_EQ(readAll(silent, 5s), "");
  EXPECT_EQ(readAll(partial, 5s), "");
  EXPECT_LT(std::chrono::steady_clock::now() - waited, 2s);
  ::close(silent);
  ::close(partial);
}

TEST_F(HttpServerTest, ConcurrentClientsAllGetAnswers) {
  start();
  std::atomic<int> ok{0};
  std::vector<std::thread> clients;
  for (int t = 0; t < 8; ++t)
    clients.emplace_back([&, t] {
      for (int i = 0; i < 25; ++i) {
        const HttpReply r = httpGet(port_, "/hello?" + std::to_string(t) + "-" + std::to_string(i));
        if (r.status == 200 && r.body == "hello " + std::to_string(t) + "-" + std::to_string(i) + "\n") ++ok;
      }
    });
  for (std::thread& c : clients) c.join();
  EXPECT_EQ(ok.load(), 200);
}

TEST_F(HttpServerTest, StopClosesTheListener) {
  start();
  server_->stop();
  EXPECT_EQ(connectLocal(port_), -1);
  server_->stop();  // idempotent
}

TEST(HttpServerAddress, BadHostOrBusyPortIsRefusedNamingTheAddress) {
  HttpServerOptions bad;
  bad.host = "localhost";  // not a dotted quad
  HttpServer a(bad);
  try {
    a.start();
    FAIL() << "started on a bad host";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("localhost:9464"), std::string::npos) << e.what();
  }

  HttpServerOptions any;
  any.port = 0;
  HttpServer first(any);
  first.start();
  HttpServerOptions same;
  same.port = first.port();
  HttpServer second(same);
  try {
    second.start();
    FAIL() << "two servers on one port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(first.port())), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("in use"), std::string::npos) << e.what();
  }
}

TEST(HttpServerAddress, DefaultsBindToLoopbackOnly) {
  EXPECT_EQ(HttpServerOptions{}.host, "127.0.0.1");
  HttpServerOptions options;
  options.port = 0;
  HttpServer s(options);
  s.start();
  EXPECT_EQ(s.address().rfind("127.0.0.1:", 0), 0u);
}

}  // namespace
}  // namespace robodiff::testing
