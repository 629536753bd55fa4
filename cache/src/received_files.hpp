// Where received entry files wait before they are verified and filed in the cache (a
// bundle's members, a fleet transfer's payload): a private scratch directory outside the
// cache, and files written there with their size and SHA-256 measured on the way, so that
// what is verified is exactly what was written. Errors throw CacheError(Io) naming the file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "robodiff/cache/entry_manifest.hpp"

namespace robodiff::cache::detail {

// A private directory (0700) under the system's temporary directory, removed with its contents.
class ScratchDir {
 public:
  // `purpose` names it: robodiff-<purpose>-XXXXXX.
  explicit ScratchDir(const std::string& purpose);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// A new file (created 0600; an existing one is refused) whose bytes are hashed as written.
class HashingFile {
 public:
  explicit HashingFile(const std::filesystem::path& to);
  ~HashingFile();  // closes it when finish() was not reached
  HashingFile(const HashingFile&) = delete;
  HashingFile& operator=(const HashingFile&) = delete;

  void write(const void* data, std::size_t size);
  std::uint64_t size() const { return size_; }
  // Closes the file; its size and lowercase hex SHA-256.
  ReceivedEntry::File finish();

 private:
  struct Digest;  // OpenSSL's context
  std::filesystem::path path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
  std::unique_ptr<Digest> digest_;
};

}  // namespace robodiff::cache::detail
