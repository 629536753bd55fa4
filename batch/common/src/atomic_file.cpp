// AtomicFile: mkstemp beside the target, write, fsync, rename, fsync the directory.
#include "robodiff/batch/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>


namespace robodiff::batch {
namespace {

constexpr std::size_t kBufferBytes = std::size_t{1} << 20;

std::string systemError() { return std::strerror(errno); }

}  // namespace

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  const std::filesystem::path dir = target_.has_parent_path() ? target_.parent_path() : std::filesystem::path(".");
  std::string name = ".";
  name += target_.filename().string();
  name += ".tmp-XXXXXX";
  std::string pattern = (dir / name).string();
  fd_ = ::mkstemp(pattern.data());
  if (fd_ < 0) throw AtomicFileError(target_.string() + ": cannot create a file in " + dir.string() + ": " + systemError());
  temp_ = pattern;
  ::fchmod(fd_, 0644);  // mkstemp makes 0600; an output file is as readable as any other
  buffer_.reserve(kBufferBytes);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
}

void AtomicFile::write(std::string_view bytes) {
  if (buffer_.size() + bytes.size() > kBufferBytes) flush();
  if (bytes.size() >= kBufferBytes) {
    buffer_.assign(bytes);
    flush();
    return;
  }
  buffer_.append(bytes);
}

void AtomicFile::flush() {
  const char* p = buffer_.data();
  std::size_t left = buffer_.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw AtomicFileError(target_.string() + ": writing failed: " + systemError());
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  buffer_.clear();
}

void AtomicFile::commit() {
  flush();
  if (::fsync(fd_) != 0) throw AtomicFileError(target_.string() + ": fsync failed: " + systemError());
  if (::close(fd_) != 0) {
    fd_ = -1;
    throw AtomicFileError(target_.string() + ": closing failed: " + systemError());
  }
  fd_ = -1;
  if (::rename(temp_.c_str(), target_.c_str()) != 0)
    throw AtomicFileError(target_.string() + ": cannot rename " + temp_.string() + " to it: " + systemError());
  committed_ = true;
  // The rename itself survives a crash once the directory is on disk.
  const std::filesystem::path dir = target_.has_parent_path() ? target_.parent_path() : std::filesystem::path(".");
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

}  // namespace robodiff::batch
