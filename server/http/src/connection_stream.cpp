#include "connection_stream.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace robodiff::server {
namespace {

constexpr std::chrono::milliseconds kLinger{500};  // draining the client after the response

void addressOf(int fd, bool peer, std::string& ip, int& port) {
  sockaddr_in address{};
  socklen_t length = sizeof address;
  const int got = peer ? ::getpeername(fd, reinterpret_cast<sockaddr*>(&address), &length)
                       : ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  char text[INET_ADDRSTRLEN] = {};
  if (got != 0 || address.sin_family != AF_INET || !::inet_ntop(AF_INET, &address.sin_addr, text, sizeof text)) return;
  ip = text;
  port = ntohs(address.sin_port);
}

}  // namespace

ConnectionStream::ConnectionStream(int fd, const ConnectionLimits& limits, int stop_fd)
    : fd_(fd), stop_fd_(stop_fd), limits_(limits), head_deadline_(Clock::now() + limits.read_timeout) {
  // httplib accepts without SOCK_CLOEXEC: keep the connection out of the build workers.
  ::fcntl(fd_, F_SETFD, ::fcntl(fd_, F_GETFD) | FD_CLOEXEC);
  // httplib writes the head and the body apart: corked, they leave together at close().
  const int one = 1;
  ::setsockopt(fd_, IPPROTO_TCP, TCP_CORK, &one, sizeof one);
}

ConnectionStream::~ConnectionStream() { close(); }

bool ConnectionStream::waitFor(short events, Clock::time_point deadline) const {
  for (;;) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    pollfd fds[2] = {{fd_, events, 0}, {stop_fd_, POLLIN, 0}};
    const int ready = ::poll(fds, 2, static_cast<int>(std::min<long long>(left, 60000)));
    if (ready < 0 && errno != EINTR) return false;
    if (fds[1].revents != 0) return !(stopping_ = true);
    if (fds[0].revents != 0) return true;  // ready, or an error recv/send reports
  }
}

bool ConnectionStream::is_readable() const {
  return buffered_begin_ < buffered_end_ || (!stopping_ && waitFor(POLLIN, head_deadline_));
}

bool ConnectionStream::is_writable() const {
  return !silent_ && !stopping_ && waitFor(POLLOUT, write_deadline_ == Clock::time_point{}
                                                        ? Clock::now() + limits_.write_timeout
                                                        : write_deadline_);
}

ssize_t ConnectionStream::read(char* ptr, size_t size) {
  if (silent_ || !problem_.empty()) return -1;
  if (buffered_begin_ == buffered_end_) {
    if (!waitFor(POLLIN, head_deadline_)) {
      silent_ = true;  // too slow, or stopping
      return -1;
    }
    const ssize_t n = ::recv(fd_, buffer_, sizeof buffer_, 0);
    if (n <= 0) return n;
    buffered_begin_ = 0;
    buffered_end_ = static_cast<std::size_t>(n);
  }
  if (head_bytes_ >= limits_.max_head_bytes) {
    problem_ = "request head over " + std::to_string(limits_.max_head_bytes) + " bytes";
    return -1;
  }
  std::size_t n = 0;
  while (n < size && buffered_begin_ < buffered_end_ && head_bytes_ < limits_.max_head_bytes) {
    char c = buffer_[buffered_begin_];
    if (c == '\n' && last_delivered_ != '\r') {
      c = '\r';  // a bare LF: a CR first, the LF itself next round
    } else {
      ++buffered_begin_;
      ++head_bytes_;
    }
    if (!checkHeadByte(c)) break;
    ptr[n++] = last_delivered_ = c;
  }
  return n == 0 ? -1 : static_cast<ssize_t>(n);
}

bool ConnectionStream::checkHeadByte(char c) {
  if (!problem_.empty()) return false;
  if (c == ':' && line_colon_ == 0) line_colon_ = line_length_ + 1;
  ++line_length_;
  if (c != '\n') return true;
  const bool header_line = line_number_++ > 0 && line_length_ > 2;  // not the request line, not the blank one
  if (header_line && line_colon_ <= 1) problem_ = "malformed header line (no 'Name:' in it)";
  line_length_ = line_colon_ = 0;
  return problem_.empty();
}

ssize_t ConnectionStream::write(const char* ptr, size_t size) {
  if (silent_ || stopping_) return -1;
  if (write_deadline_ == Clock::time_point{}) write_deadline_ = Clock::now() + limits_.write_timeout;
  for (;;) {
    if (!waitFor(POLLOUT, write_deadline_)) return -1;
    const ssize_t n = ::send(fd_, ptr, size, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n >= 0 || (errno != EAGAIN && errno != EINTR)) {
      answered_ = answered_ || n > 0;
      return n;
    }
  }
}

void ConnectionStream::get_remote_ip_and_port(std::string& ip, int& port) const { addressOf(fd_, true, ip, port); }

void ConnectionStream::get_local_ip_and_port(std::string& ip, int& port) const { addressOf(fd_, false, ip, port); }

void ConnectionStream::close() {
  if (fd_ < 0) return;
  if (answered_ && !stopping_) {
    ::shutdown(fd_, SHUT_WR);  // sends what the cork held, then FIN
    const auto until = Clock::now() + kLinger;
    char discard[4096];
    while (waitFor(POLLIN, until) && ::recv(fd_, discard, sizeof discard, 0) > 0) {
    }
  }
  ::close(fd_);
  fd_ = -1;
}

}  // namespace robodiff::server
