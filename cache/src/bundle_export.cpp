// Writing signed cache entries into one tar bundle with libarchive (artifact_bundle.hpp).
#include <archive.h>
#include <archive_entry.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "robodiff/cache/artifact_bundle.hpp"
#include "robodiff/cache/entry_transfer.hpp"

namespace robodiff::cache {

namespace fs = std::filesystem;

namespace {

std::int64_t unixNow() {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// A libarchive writer onto an open file descriptor.
class TarWriter {
 public:
  TarWriter(int fd, const fs::path& file) : a_(archive_write_new(), archive_write_free), file_(file) {
    if (archive_write_set_format_pax_restricted(a_.get()) != ARCHIVE_OK || archive_write_open_fd(a_.get(), fd) != ARCHIVE_OK)
      fail("cannot start");
  }
  void add(const std::string& name, const std::string& bytes, std::int64_t mtime) {
    std::unique_ptr<archive_entry, decltype(&archive_entry_free)> e(archive_entry_new(), archive_entry_free);
    archive_entry_set_pathname(e.get(), name.c_str());
    archive_entry_set_size(e.get(), static_cast<la_int64_t>(bytes.size()));
    archive_entry_set_filetype(e.get(), AE_IFREG);
    archive_entry_set_perm(e.get(), 0644);
    archive_entry_set_mtime(e.get(), mtime, 0);
    if (archive_write_header(a_.get(), e.get()) != ARCHIVE_OK) fail("cannot write the header of " + name + " to");
    if (!bytes.empty() && archive_write_data(a_.get(), bytes.data(), bytes.size()) != static_cast<la_ssize_t>(bytes.size()))
      fail("cannot write " + name + " to");
  }
  void close() {
    if (archive_write_close(a_.get()) != ARCHIVE_OK) fail("cannot finish");
  }

 private:
  [[noreturn]] void fail(const std::string& what) {
    const char* detail = archive_error_string(a_.get());
    throw CacheError(CacheError::Kind::Io, what + " the bundle " + file_.string() + ": " + (detail ? detail : "unknown error"));
  }
  std::unique_ptr<archive, decltype(&archive_write_free)> a_;
  fs::path file_;
};

// Adds one signed entry, with its sources, to the bundle.
void writeEntry(TarWriter& tar, const Artifact& artifact, const SigningKey& signer, std::int64_t now) {
  const SignedEntry entry = signEntry(artifact, signer, /*include_sources=*/true, now);
  const std::string dir = artifact.key() + "/";
  tar.add(dir + kManifestName, entry.manifest, now);
  tar.add(dir + kSignatureName, entry.signature_hex + "\n", now);
  for (const EntryFile& f : entry.files) tar.add(dir + f.name, f.bytes, now);
}

}  // namespace

ExportReport exportBundle(Cache& cache, const std::vector<std::string>& keys, const SigningKey& signer,
                          const fs::path& out) {
  // Every entry is found and verified before the file is started: a bad key writes nothing.
  std::vector<Artifact> artifacts;
  for (const std::string& key : keys)
    if (std::none_of(artifacts.begin(), artifacts.end(), [&](const Artifact& a) { return a.key() == key; }))
      artifacts.push_back(exportableArtifact(cache, key));  // once each: a key named twice is one entry

  const fs::path partial = out.string() + ".partial";
  const int fd = ::open(partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw CacheError(CacheError::Kind::Io, "cannot create " + partial.string() + ": " + std::strerror(errno));
  ExportReport report;
  bool fd_open = true;
  try {
    const std::int64_t now = unixNow();
    TarWriter tar(fd, out);
    nlohmann::json index = nlohmann::json::array();
    for (const Artifact& a : artifacts) {
      writeEntry(tar, a, signer, now);
      index.push_back(a.key());
      report.exported.push_back(a.entry());
    }
    tar.add(kBundleIndexName, nlohmann::json{{"format", 1}, {"entries", index}}.dump() + "\n", now);
    tar.close();
    if (::fsync(fd) != 0)
      throw CacheError(CacheError::Kind::Io, "cannot fsync " + partial.string() + ": " + std::strerror(errno));
    fd_open = false;
    ::close(fd);
    if (::rename(partial.c_str(), out.c_str()) != 0)
      throw CacheError(CacheError::Kind::Io, "cannot rename " + partial.string() + " to " + out.string() + ": " +
                                                 std::strerror(errno));
  } catch (...) {
    if (fd_open) ::close(fd);
    ::unlink(partial.c_str());
    throw;
  }
  report.bytes = fs::file_size(out);
  return report;
}

}  // namespace robodiff::cache
