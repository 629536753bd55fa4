// Reading a tar bundle of signed cache entries with libarchive, verifying each entry and
// publishing the good ones (artifact_bundle.hpp). Files are read into a private
// temporary directory outside the cache, hashed on the way; nothing reaches the cache
// before its entry is verified, and then only through claim/publish.
#include <archive.h>
#include <archive_entry.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "artifact_files.hpp"
#include "received_files.hpp"
#include "robodiff/cache/artifact_bundle.hpp"
#include "robodiff/cache/cache_key.hpp"
#include "robodiff/cache/entry_manifest.hpp"

namespace robodiff::cache {

namespace fs = std::filesystem;

std::size_t ImportReport::count(ImportResult::Status status) const {
  return static_cast<std::size_t>(
      std::count_if(entries.begin(), entries.end(), [&](const ImportResult& r) { return r.status == status; }));
}

namespace {

constexpr std::uint64_t kMaxSignatureBytes = 1024;

using Archive = std::unique_ptr<archive, decltype(&archive_read_free)>;

// One entry as its members arrive.
struct Pending {
  ReceivedEntry received;
  fs::path dir;         // its files, under the scratch directory
  std::string problem;  // refused while reading (then its files are gone)
};

// What reading the archive found.
struct Contents {
  std::vector<std::string> order;  // entry keys by first appearance
  std::map<std::string, Pending> entries;
  std::vector<ImportResult> strays;  // members of no entry, a truncated or malformed bundle
  std::optional<std::vector<std::string>> index;  // bundle.json's keys
};

std::string archiveError(archive* a) {
  const char* e = archive_error_string(a);
  return e ? e : "unknown error";
}

// Reads the current member into memory (its declared size already checked).
std::optional<std::string> readSmall(archive* a, std::string& error) {
  std::string bytes;
  char buf[4096];
  for (;;) {
    const la_ssize_t n = archive_read_data(a, buf, sizeof buf);
    if (n == 0) return bytes;
    if (n < 0) {
      error = archiveError(a);
      return std::nullopt;
    }
    bytes.append(buf, static_cast<std::size_t>(n));
  }
}

// Streams the current member into `to` (created 0600), measuring its size and SHA-256.
std::optional<ReceivedEntry::File> readToFile(archive* a, const fs::path& to, std::string& error) {
  detail::HashingFile file(to);
  std::vector<char> buf(1 << 16);
  for (;;) {
    const la_ssize_t n = archive_read_data(a, buf.data(), buf.size());
    if (n == 0) return file.finish();
    if (n < 0) {
      error = archiveError(a);
      return std::nullopt;
    }
    file.write(buf.data(), static_cast<std::size_t>(n));
  }
}

// Refuses an entry while reading: its files are dropped at once.
void refuse(Pending& p, const std::string& problem) {
  if (!p.problem.empty()) return;
  p.problem = problem;
  detail::removeTreeQuietly(p.dir);
}

ImportResult refused(const std::string& key, const std::string& problem) {
  ImportResult r;
  r.key = key;
  r.problem = problem;
  return r;
}

// What is wrong with a member's header before any of its bytes is read, or empty.
std::string headerProblem(archive_entry* e, const std::string& name, const std::string& file, std::uint64_t limit) {
  if (archive_entry_filetype(e) != AE_IFREG || archive_entry_hardlink(e) != nullptr ||
      archive_entry_symlink(e) != nullptr)
    return "member " + name + " is not a regular file (a link, directory or device)";
  if (!archive_entry_size_is_set(e)) return "member " + name + " has no size";
  const la_int64_t size = archive_entry_size(e);
  if (size < 0 || static_cast<std::uint64_t>(size) > limit)
    return "member " + name + " declares " + std::to_string(size) + " bytes, more than the limit of " +
           std::to_string(limit) + " for " + file + "; not read";
  return {};
}

class BundleReader {
 public:
  BundleReader(archive* a, const fs::path& scratch, const BundleLimits& limits)
      : a_(a), scratch_(scratch), limits_(limits) {}

  // Reads every member; false when the archive broke off (truncated or corrupt).
  bool read(Contents& out) {
    for (;;) {
      archive_entry* e = nullptr;
      const int r = archive_read_next_header(a_, &e);
      if (r == ARCHIVE_EOF) return true;
      if (r < ARCHIVE_WARN) {
        out.strays.push_back(refused(kBundleIndexName, "truncated or corrupt bundle: " + archiveError(a_) +
                                                           "; entries after this point are missing"));
        return false;
      }
      const char* raw = archive_entry_pathname(e);
      const std::string name = raw ? raw : "";
      if (!member(out, e, name)) {
        out.strays.push_back(refused(kBundleIndexName, "truncated or corrupt bundle: it breaks off inside " + name +
                                                           "; entries after this point are missing"));
        return false;
      }
    }
  }

 private:
  // Handles one member; false when reading its data failed (the bundle ends there).
  bool member(Contents& out, archive_entry* e, const std::string& name) {
    if (name == kBundleIndexName) return indexMember(out, e);
    const auto slash = name.find('/');
    const std::string key = name.substr(0, slash);
    if (slash == std::string::npos || !isCacheKey(key)) {
      out.strays.push_back(refused(name, "member \"" + name + "\" belongs to no entry (expected <key>/<file>)"));
      archive_read_data_skip(a_);
      return true;
    }
    auto [it, fresh] = out.entries.try_emplace(key);
    Pending& p = it->second;
    if (fresh) {
      if (out.order.size() >= limits_.max_entries) {
        out.entries.erase(it);
        out.strays.push_back(refused(key, "more than " + std::to_string(limits_.max_entries) + " entries in the bundle"));
        return true;
      }
      out.order.push_back(key);
      p.received.key = key;
      p.dir = scratch_ / key;
      if (::mkdir(p.dir.c_str(), 0700) != 0) refuse(p, "cannot create " + p.dir.string() + ": " + std::strerror(errno));
    }
    if (!p.problem.empty()) return skip();
    return entryMember(p, e, name, name.substr(slash + 1));
  }

  bool entryMember(Pending& p, archive_entry* e, const std::string& name, const std::string& file) {
    const bool signing = file == kManifestName || file == kSignatureName;
    if (!signing && !isEntryFileName(file)) {
      refuse(p, "unsafe member name \"" + name + "\" (path traversal, or not an entry file)");
      return skip();
    }
    const std::uint64_t limit = file == kSignatureName ? kMaxSignatureBytes
                                : file == kManifestName ? limits_.max_manifest_bytes
                                                        : limits_.max_file_bytes;
    if (const std::string problem = headerProblem(e, name, file, limit); !problem.empty()) {
      refuse(p, problem);
      return skip();
    }
    const bool duplicate = file == kManifestName   ? p.received.manifest.has_value()
                           : file == kSignatureName ? p.received.signature.has_value()
                                                    : p.received.files.count(file) > 0;
    if (duplicate) {
      refuse(p, "member " + name + " appears twice");
      return skip();
    }
    if (p.received.files.size() >= limits_.max_files_per_entry) {
      refuse(p, "more than " + std::to_string(limits_.max_files_per_entry) + " files");
      return skip();
    }
    std::string error;
    if (signing) {
      std::optional<std::string> bytes = readSmall(a_, error);
      if (bytes) (file == kManifestName ? p.received.manifest : p.received.signature) = std::move(*bytes);
    } else {
      if (file.rfind("src/", 0) == 0) ::mkdir((p.dir / "src").c_str(), 0700);
      if (std::optional<ReceivedEntry::File> f = readToFile(a_, p.dir / file, error)) p.received.files[file] = *f;
    }
    if (error.empty()) return true;
    refuse(p, "truncated: the bundle breaks off inside " + name + " (" + error + ")");
    return false;
  }

  bool indexMember(Contents& out, archive_entry* e) {
    std::string error;
    std::optional<std::string> text;
    if (headerProblem(e, kBundleIndexName, kBundleIndexName, limits_.max_manifest_bytes).empty())
      text = readSmall(a_, error);
    const nlohmann::json j = nlohmann::json::parse(text.value_or(""), nullptr, false);
    if (!error.empty() || j.is_discarded() || !j.contains("entries") || !j["entries"].is_array()) {
      out.strays.push_back(refused(kBundleIndexName, "bundle.json is unreadable or malformed"));
      return error.empty();
    }
    out.index.emplace();
    for (const nlohmann::json& k : j["entries"])
      if (k.is_string()) out.index->push_back(k);
    return true;
  }

  bool skip() {
    archive_read_data_skip(a_);
    return true;
  }

  archive* a_;
  fs::path scratch_;
  const BundleLimits& limits_;
};

}  // namespace

ImportReport importBundle(Cache& cache, const fs::path& bundle, const TrustedKeys& trusted, const BundleLimits& limits) {
  Archive a(archive_read_new(), archive_read_free);
  archive_read_support_format_tar(a.get());
  if (archive_read_open_filename(a.get(), bundle.c_str(), 1 << 16) != ARCHIVE_OK)
    throw std::runtime_error("cannot open the bundle " + bundle.string() + ": " + archiveError(a.get()));
  detail::ScratchDir scratch("import");
  Contents contents;
  const bool complete = BundleReader(a.get(), scratch.path(), limits).read(contents);
  a.reset();

  ImportReport report;
  for (const std::string& key : contents.order) {
    Pending& p = contents.entries.at(key);
    if (!p.problem.empty()) {
      report.entries.push_back(refused(key, p.problem));
      continue;
    }
    const ManifestCheck check = verifyReceivedEntry(p.received, trusted);
    report.entries.push_back(check.manifest ? installVerifiedEntry(cache, *check.manifest, p.dir) : refused(key, check.problem));
    detail::removeTreeQuietly(p.dir);
  }
  // Cut short: at an entry boundary, bundle.json (written last) is what is missing.
  if (complete && !contents.index)
    contents.strays.push_back(
        refused(kBundleIndexName, "truncated: the bundle ends before its closing bundle.json; entries may be missing"));
  if (contents.index)
    for (const std::string& key : *contents.index)
      if (!contents.entries.count(key)) contents.strays.push_back(refused(key, "listed in bundle.json but missing from the bundle"));
  report.entries.insert(report.entries.end(), contents.strays.begin(), contents.strays.end());
  return report;
}

}  // namespace robodiff::cache
