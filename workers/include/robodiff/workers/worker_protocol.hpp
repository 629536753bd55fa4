// The wire format between the pool and a robodiff-worker: frames, each a 4-byte
// little-endian length followed by that many bytes of JSON, over the worker's stdin
// (requests) and stdout (replies).
//
// Requests (the pool adds "id" and "limits"):
//   {"id": N, "type": "build", "limits": {"memory_bytes": B}, "request": {...}}
//     request: a BuildRequest (build_job.hpp, toJson)
//   {"id": N, "type": "ping", "limits": {...}}  a health check
// A worker runs each request under its limits (RLIMIT_AS), then lifts them.
// Replies, for the request with the same id:
//   {"id": N, "type": "progress", "stage": "trace"}      any number, before the result
//   {"id": N, "type": "result", "ok": true|false, ...}   exactly one
//     build: the BuildOutcome's fields (build_job.hpp); ping: "pid" and
//     "address_space_limit_bytes" (the limit it ran under, 0: none); any failure: "message"
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace robodiff::workers {

// Largest frame either side accepts (a URDF with its meshes' names is far smaller).
inline constexpr std::size_t kMaxFrameBytes = std::size_t{64} << 20;

// A frame that cannot be read or written: end of file inside a frame, a length past the
// limit, a read or write error (the message has errno's text).
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The bytes of one frame: the length prefix, then the payload. Throws ProtocolError when
// the payload is larger than max_bytes.
std::string encodeFrame(std::string_view payload, std::size_t max_bytes = kMaxFrameBytes);

// Writes one whole frame to a blocking fd, retrying after EINTR and short writes.
// Throws ProtocolError (EPIPE included: the caller decides about SIGPIPE).
void writeFrame(int fd, std::string_view payload, std::size_t max_bytes = kMaxFrameBytes);

// Reads one whole frame from a blocking fd, retrying after EINTR and short reads.
// nullopt: end of file before the first byte of a frame (the other side closed cleanly).
// Throws ProtocolError on end of file inside a frame, a length past max_bytes, or a read
// error.
std::optional<std::string> readFrame(int fd, std::size_t max_bytes = kMaxFrameBytes);

// Splits a byte stream read in pieces (from a non-blocking fd) into frames.
class FrameDecoder {
 public:
  explicit FrameDecoder(std::size_t max_bytes = kMaxFrameBytes) : max_bytes_(max_bytes) {}

  void append(const char* data, std::size_t size) { buffer_.append(data, size); }
  // The next complete frame's payload, if one is buffered. Throws ProtocolError when the
  // next frame's length is past the limit.
  std::optional<std::string> next();
  // Bytes of an incomplete frame are buffered: end of file now would truncate it.
  bool partial() const { return buffer_.size() > consumed_; }

 private:
  std::size_t max_bytes_;
  std::string buffer_;
  std::size_t consumed_ = 0;  // bytes of buffer_ already handed out as frames
};

// Requests a pool may submit (WorkerPool::submit adds "id" and "limits").
std::string pingRequest();
// `build_request_json`: toJson(BuildRequest).
std::string buildRequestMessage(const std::string& build_request_json);

}  // namespace robodiff::workers
