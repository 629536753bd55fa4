// A minimal HTTP client for tests: one request over a fresh TCP connection to 127.0.0.1,
// the whole response read until the server closes (it always sends Connection: close).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cstdlib>
#include <cstdint>
#include <string>

namespace robodiff::testing {

struct HttpReply {
  int status = 0;  // 0: no status line (connection refused, closed or timed out)
  std::string head, body;
  std::string header(const std::string& name) const {  // case-insensitive, first match
    std::string lower_head, lower_name;
    for (char c : head) lower_head += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    for (char c : name) lower_name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const auto at = lower_head.find("\r\n" + lower_name + ":");
    if (at == std::string::npos) return "";
    const auto begin = head.find_first_not_of(' ', at + 2 + name.size() + 1);
    return head.substr(begin, head.find("\r\n", begin) - begin);
  }
};

// A connected socket to 127.0.0.1:port, or -1.
inline int connectLocal(std::uint16_t port, const char* host = "127.0.0.1") {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  ::inet_pton(AF_INET, host, &a.sin_addr);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// Reads until the peer closes or `timeout` passes; returns what came.
inline std::string readAll(int fd, std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  std::string out;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  char buffer[8192];
  while (true) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) break;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    out.append(buffer, static_cast<std::size_t>(n));
  }
  return out;
}

inline HttpReply parseReply(const std::string& raw) {
  HttpReply r;
  const auto end = raw.find("\r\n\r\n");
  if (raw.rfind("HTTP/1.1 ", 0) != 0 || end == std::string::npos) return r;
  r.status = std::atoi(raw.c_str() + 9);
  r.head = raw.substr(0, end + 2);
  r.body = raw.substr(end + 4);
  return r;
}

// Sends `raw` as is and reads the reply.
inline HttpReply rawRequest(std::uint16_t port, const std::string& raw,
                            std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  const int fd = connectLocal(port);
  if (fd < 0) return {};
  ::send(fd, raw.data(), raw.size(), MSG_NOSIGNAL);
  const std::string reply = readAll(fd, timeout);
  ::close(fd);
  return parseReply(reply);
}

inline HttpReply httpGet(std::uint16_t port, const std::string& path, const std::string& method = "GET") {
  return rawRequest(port, method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nUser-Agent: robodiff-test\r\n\r\n");
}

}  // namespace robodiff::testing
