// Scratch directories and hashed writes for received entry files (received_files.hpp).
#include "received_files.hpp"

#include <fcntl.h>
#include <openssl/evp.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "artifact_files.hpp"

namespace robodiff::cache::detail {

namespace fs = std::filesystem;

ScratchDir::ScratchDir(const std::string& purpose) {
  std::string pattern = (fs::temp_directory_path() / ("robodiff-" + purpose + "-XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr)  // mkdtemp makes it 0700
    throw CacheError(CacheError::Kind::Io, "cannot create a temporary directory in " +
                                               fs::temp_directory_path().string() + ": " + std::strerror(errno));
  path_ = pattern;
}

ScratchDir::~ScratchDir() { removeTreeQuietly(path_); }

struct HashingFile::Digest {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx{EVP_MD_CTX_new(), EVP_MD_CTX_free};
};

HashingFile::HashingFile(const fs::path& to) : path_(to), digest_(std::make_unique<Digest>()) {
  if (!digest_->ctx || EVP_DigestInit_ex(digest_->ctx.get(), EVP_sha256(), nullptr) != 1)
    throw CacheError(CacheError::Kind::Io, "cannot start a SHA-256 for " + to.string());
  fd_ = ::open(to.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd_ < 0) throw CacheError(CacheError::Kind::Io, "cannot create " + to.string() + ": " + std::strerror(errno));
}

HashingFile::~HashingFile() {
  if (fd_ >= 0) ::close(fd_);
}

void HashingFile::write(const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  std::size_t left = size;
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw CacheError(CacheError::Kind::Io, "cannot write " + path_.string() + ": " + std::strerror(errno));
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  EVP_DigestUpdate(digest_->ctx.get(), data, size);
  size_ += size;
}

ReceivedEntry::File HashingFile::finish() {
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) throw CacheError(CacheError::Kind::Io, "cannot close " + path_.string() + ": " + std::strerror(errno));
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned length = 0;
  EVP_DigestFinal_ex(digest_->ctx.get(), digest, &length);
  return {size_, toHex(std::string(reinterpret_cast<const char*>(digest), length))};
}

}  // namespace robodiff::cache::detail
