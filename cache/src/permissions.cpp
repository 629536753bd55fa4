#include "permissions.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

#include "robodiff/cache/cache.hpp"

namespace robodiff::cache::detail {

namespace fs = std::filesystem;

std::string modeText(unsigned mode) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04o", mode & 07777u);
  return buf;
}

namespace {

[[noreturn]] void refuse(const std::string& message) { throw CacheError(CacheError::Kind::Permissions, message); }

void checkOwnerAndMode(const fs::path& path, const struct stat& st, const char* what) {
  const uid_t me = geteuid();
  if (st.st_uid != me && st.st_uid != 0)
    refuse("cache " + std::string(what) + " " + path.string() + " is owned by user id " + std::to_string(st.st_uid) +
           ", not by this user (" + std::to_string(me) +
           "); robodiff loads compiled code from the cache and only trusts files it owns");
  if (st.st_mode & (S_IWGRP | S_IWOTH))
    refuse("cache " + std::string(what) + " " + path.string() + " is writable by " +
           ((st.st_mode & S_IWOTH) ? "other users" : "its group") + " (mode " + modeText(st.st_mode) +
           "); robodiff loads compiled code from it and refuses; run: chmod go-w " + path.string());
}

}  // namespace

void preparePrivateDirectory(const fs::path& dir, bool create) {
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) {
    const int err = errno;
    if (err != ENOENT || !create)
      refuse("cannot use cache directory " + dir.string() + ": " + std::strerror(err));
    // Parents as usual; the cache directory itself private.
    std::error_code ec;
    if (dir.has_parent_path()) fs::create_directories(dir.parent_path(), ec);
    if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST)
      refuse("cannot create cache directory " + dir.string() + ": " + std::strerror(errno));
    if (::stat(dir.c_str(), &st) != 0)
      refuse("cannot use cache directory " + dir.string() + ": " + std::strerror(errno));
  }
  if (!S_ISDIR(st.st_mode)) refuse("cache directory " + dir.string() + " exists and is not a directory");
  checkOwnerAndMode(dir, st, "directory");
  // Root passes access(W_OK) regardless of the mode bits, so the owner-write bit is
  // checked as well: a directory its owner made read-only is not meant to be written.
  if (!(st.st_mode & S_IWUSR) || ::access(dir.c_str(), W_OK | X_OK) != 0)
    refuse("cache directory " + dir.string() + " is not writable (mode " + modeText(st.st_mode) +
           "); give its owner write permission (chmod u+rwx) or choose another with --cache / ROBODIFF_CACHE_DIR");
}

void checkNotWritableByOthers(const fs::path& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0)
    refuse("cannot check " + path.string() + " before loading it: " + std::strerror(errno));
  if (S_ISLNK(st.st_mode)) refuse("cache file " + path.string() + " is a symbolic link; robodiff refuses to load it");
  checkOwnerAndMode(path, st, S_ISDIR(st.st_mode) ? "directory" : "file");
}

}  // namespace robodiff::cache::detail
