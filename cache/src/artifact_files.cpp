#include "artifact_files.hpp"

#include <fcntl.h>
#include <openssl/evp.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

#include "robodiff/cache/cache.hpp"

namespace robodiff::cache::detail {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void ioError(const std::string& what, const fs::path& path, int err) {
  throw CacheError(CacheError::Kind::Io, what + " " + path.string() + ": " + std::strerror(err));
}

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ioError("cannot read", path, errno ? errno : ENOENT);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Writes bytes to a new file and fsyncs it before closing.
void writeSynced(const fs::path& to, const void* data, std::size_t size, unsigned mode) {
  const int fd = ::open(to.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, mode);
  if (fd < 0) ioError("cannot create", to, errno);
  const char* p = static_cast<const char*>(data);
  std::size_t left = size;
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      ioError("cannot write", to, err);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    ioError("cannot fsync", to, err);
  }
  ::fchmod(fd, mode);  // the umask must not widen or narrow what the cache decided
  if (::close(fd) != 0) ioError("cannot close", to, errno);
}

}  // namespace

void copyFileSynced(const fs::path& from, const fs::path& to, unsigned mode) {
  const std::string bytes = readAll(from);
  writeSynced(to, bytes.data(), bytes.size(), mode);
}

void compressFileSynced(const fs::path& from, const fs::path& to) {
  const std::string bytes = readAll(from);
  std::vector<char> packed(ZSTD_compressBound(bytes.size()));
  const std::size_t n = ZSTD_compress(packed.data(), packed.size(), bytes.data(), bytes.size(), 3);
  if (ZSTD_isError(n))
    throw CacheError(CacheError::Kind::Io, "cannot compress " + from.string() + ": " + ZSTD_getErrorName(n));
  writeSynced(to, packed.data(), n, 0600);
}

void writeFileSynced(const fs::path& to, const std::string& text) { writeSynced(to, text.data(), text.size(), 0600); }

std::string decompressFile(const fs::path& path) {
  const std::string packed = readAll(path);
  const unsigned long long size = ZSTD_getFrameContentSize(packed.data(), packed.size());
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN)
    throw CacheError(CacheError::Kind::Io, "cannot decompress " + path.string() + ": not a zstd frame with a size");
  std::string out(size, '\0');
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), packed.data(), packed.size());
  if (ZSTD_isError(n))
    throw CacheError(CacheError::Kind::Io, "cannot decompress " + path.string() + ": " + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

void fsyncDirectory(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) ioError("cannot open directory", dir, errno);
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) ioError("cannot fsync directory", dir, err);
}

std::string sha256OfFile(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) ioError("cannot read", path, errno);
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr);
  std::vector<unsigned char> buf(1 << 16);
  for (;;) {
    const ssize_t n = ::read(fd, buf.data(), buf.size());
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      ioError("cannot read", path, err);
    }
    EVP_DigestUpdate(ctx.get(), buf.data(), static_cast<std::size_t>(n));
  }
  ::close(fd);
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned length = 0;
  EVP_DigestFinal_ex(ctx.get(), digest, &length);
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned i = 0; i < length; ++i) {
    out += hex[digest[i] >> 4];
    out += hex[digest[i] & 15];
  }
  return out;
}

std::uint64_t directoryBytes(const fs::path& dir) {
  std::error_code ec;
  std::uint64_t total = 0;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->is_regular_file(ec)) total += it->file_size(ec);
  }
  return total;
}

void removeTreeQuietly(const fs::path& path) noexcept {
  std::error_code ec;
  fs::remove_all(path, ec);
}

}  // namespace robodiff::cache::detail
