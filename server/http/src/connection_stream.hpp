#pragma once
// One accepted connection as httplib reads and writes it, with robodiff's limits: the
// whole request head must arrive within the read timeout and may not exceed
// max_head_bytes (httplib 0.11 only bounds each read and each line); the whole response
// must leave within the write timeout; and a stop signal (an eventfd) ends every wait.
// A connection whose head timed out gets no answer (it is just closed). Two things httplib
// 0.11 does not do are done here as the head passes: a bare LF ends a line as CRLF does
// (RFC 9112 2.2 allows it), and a header line without a name and ':' is refused (httplib
// would skip it).
#include <httplib.h>

#include <chrono>
#include <cstddef>
#include <string>

namespace robodiff::server {

struct ConnectionLimits {
  std::size_t max_head_bytes = 8192;
  std::chrono::milliseconds read_timeout{5000};   // for the whole head
  std::chrono::milliseconds write_timeout{5000};  // for the whole response
};

class ConnectionStream final : public httplib::Stream {
 public:
  using Clock = std::chrono::steady_clock;

  // Takes `fd` (closed by close()); `stop_fd` readable means the server stops.
  ConnectionStream(int fd, const ConnectionLimits& limits, int stop_fd);
  ~ConnectionStream() override;  // close()

  bool is_readable() const override;
  bool is_writable() const override;
  ssize_t read(char* ptr, size_t size) override;
  ssize_t write(const char* ptr, size_t size) override;
  void get_remote_ip_and_port(std::string& ip, int& port) const override;
  void get_local_ip_and_port(std::string& ip, int& port) const override;
  socket_t socket() const override { return fd_; }

  // Why reading stopped early ("request head over 8192 bytes"); empty otherwise.
  const std::string& problem() const { return problem_; }
  // Half-closes, reads what the client still sends for a moment (closing with unread
  // input would reset the connection and lose the response), then closes. Idempotent.
  void close();

 private:
  // Checks one byte of the head on its way to httplib; false (and problem_) when its line
  // is malformed.
  bool checkHeadByte(char c);
  // Waits until the socket has `events` or `deadline` passes; false on timeout or stop.
  bool waitFor(short events, Clock::time_point deadline) const;

  int fd_;
  int stop_fd_;
  ConnectionLimits limits_;
  Clock::time_point head_deadline_;
  Clock::time_point write_deadline_{};
  std::size_t head_bytes_ = 0;  // handed to httplib so far
  char buffer_[4096];
  std::size_t buffered_begin_ = 0, buffered_end_ = 0;
  char last_delivered_ = 0;
  std::size_t line_number_ = 0, line_length_ = 0, line_colon_ = 0;  // line_colon_: 1 + its index, 0: none
  bool silent_ = false;    // the head did not arrive in time, or the server stops: no answer
  bool answered_ = false;  // something was written
  mutable bool stopping_ = false;
  std::string problem_;
};

}  // namespace robodiff::server
