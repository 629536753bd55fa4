#include "robodiff/workers/worker_protocol.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <nlohmann/json.hpp>

namespace robodiff::workers {
namespace {

constexpr std::size_t kHeaderBytes = 4;

std::string mib(std::size_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

std::uint32_t decodeLength(const unsigned char* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

void checkLength(std::size_t length, std::size_t max_bytes) {
  if (length > max_bytes)
    throw ProtocolError("frame of " + std::to_string(length) + " bytes is past the limit of " +
                        std::to_string(max_bytes) + " bytes (" + mib(max_bytes) + ")");
}

// Reads exactly `size` bytes unless end of file comes first; returns the count read.
std::size_t readFully(int fd, char* data, std::size_t size) {
  std::size_t got = 0;
  while (got < size) {
    const ssize_t n = ::read(fd, data + got, size - got);
    if (n > 0) {
      got += static_cast<std::size_t>(n);
    } else if (n == 0) {
      break;
    } else if (errno != EINTR) {
      throw ProtocolError(std::string("reading a frame from fd ") + std::to_string(fd) + ": " + std::strerror(errno));
    }
  }
  return got;
}

}  // namespace

std::string encodeFrame(std::string_view payload, std::size_t max_bytes) {
  checkLength(payload.size(), max_bytes);
  const auto length = static_cast<std::uint32_t>(payload.size());
  std::string frame(kHeaderBytes, '\0');
  for (std::size_t i = 0; i < kHeaderBytes; ++i) frame[i] = static_cast<char>((length >> (8 * i)) & 0xff);
  frame.append(payload);
  return frame;
}

void writeFrame(int fd, std::string_view payload, std::size_t max_bytes) {
  const std::string frame = encodeFrame(payload, max_bytes);
  std::size_t written = 0;
  while (written < frame.size()) {
    const ssize_t n = ::write(fd, frame.data() + written, frame.size() - written);
    if (n >= 0) {
      written += static_cast<std::size_t>(n);
    } else if (errno != EINTR) {
      throw ProtocolError(std::string("writing a frame of ") + std::to_string(payload.size()) + " bytes to fd " +
                          std::to_string(fd) + ": " + std::strerror(errno));
    }
  }
}

std::optional<std::string> readFrame(int fd, std::size_t max_bytes) {
  unsigned char header[kHeaderBytes];
  const std::size_t got = readFully(fd, reinterpret_cast<char*>(header), kHeaderBytes);
  if (got == 0) return std::nullopt;
  if (got < kHeaderBytes)
    throw ProtocolError("end of file inside a frame's length (" + std::to_string(got) + " of 4 bytes)");
  const std::uint32_t length = decodeLength(header);
  checkLength(length, max_bytes);
  std::string payload(length, '\0');
  const std::size_t body = readFully(fd, payload.data(), length);
  if (body < length)
    throw ProtocolError("end of file inside a frame: " + std::to_string(body) + " of " + std::to_string(length) +
                        " bytes");
  return payload;
}

std::optional<std::string> FrameDecoder::next() {
  const std::size_t available = buffer_.size() - consumed_;
  if (available < kHeaderBytes) return std::nullopt;
  const std::uint32_t length = decodeLength(reinterpret_cast<const unsigned char*>(buffer_.data() + consumed_));
  checkLength(length, max_bytes_);
  if (available - kHeaderBytes < length) return std::nullopt;
  std::string payload = buffer_.substr(consumed_ + kHeaderBytes, length);
  consumed_ += kHeaderBytes + length;
  // Drop consumed bytes once they are the larger part of the buffer (amortised O(1)).
  if (consumed_ > buffer_.size() / 2) {
    buffer_.erase(0, consumed_);
    consumed_ = 0;
  }
  return payload;
}

std::string pingRequest() { return nlohmann::json{{"type", "ping"}}.dump(); }

std::string buildRequestMessage(const std::string& build_request_json) {
  return nlohmann::json{{"type", "build"}, {"request", nlohmann::json::parse(build_request_json)}}.dump();
}

}  // namespace robodiff::workers
