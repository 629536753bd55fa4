// Signed cache entries moved as one file (an air-gapped robot, a container image): a tar
// archive (POSIX pax, written and read with libarchive) holding, per entry,
//   <key>/manifest.json    the signed manifest (entry_manifest.hpp), canonical JSON
//   <key>/manifest.sig     its Ed25519 signature, 128 lowercase hex digits and a newline
//   <key>/library.so, <key>/description.json, <key>/src/<name>   the files it lists
// and last, bundle.json: {"format": 1, "entries": [keys]}, so that a bundle cut short at
// an entry boundary is still seen as truncated.
//
// Import checks each entry before anything touches the cache: a signature by a trusted
// key; the manifest's key = the directory's name; each member a plain regular file with
// an entry file name (no path traversal, no links); sizes within BundleLimits (refused
// from the header, before any byte is read); each file's size and SHA-256 = the signed
// ones; no missing or extra file. A good entry goes through claim/publish, so it appears
// whole or not at all; one already present and intact is left alone. A refused entry
// leaves nothing in the cache; other entries of the bundle still import.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/entry_transfer.hpp"  // ImportResult

namespace robodiff::cache {

struct BundleLimits {
  std::uint64_t max_file_bytes = std::uint64_t{1} << 30;  // one entry file (library.so, ...)
  std::uint64_t max_manifest_bytes = std::uint64_t{1} << 20;
  std::uint64_t max_files_per_entry = 4096;
  std::uint64_t max_entries = 100000;
};

struct ExportReport {
  std::vector<Entry> exported;  // in bundle order
  std::uint64_t bytes = 0;      // the bundle file's size
};

// Writes the verified entries `keys` (full keys) to `out`, each signed with `signer`.
// The file appears complete or not at all (written beside it, then renamed). Throws
// std::runtime_error naming the key when one is absent, being built or fails
// verification, and CacheError(Io) when the file cannot be written.
ExportReport exportBundle(Cache& cache, const std::vector<std::string>& keys, const SigningKey& signer,
                          const std::filesystem::path& out);

struct ImportReport {
  std::vector<ImportResult> entries;  // in bundle order
  std::size_t count(ImportResult::Status status) const;
  bool allAccepted() const { return count(ImportResult::Status::Refused) == 0; }
};

// Verifies and files every entry of `bundle` into `cache`. Problems with one entry (or
// a member that belongs to none) are Refused results; throws std::runtime_error only when
// the bundle cannot be opened at all.
ImportReport importBundle(Cache& cache, const std::filesystem::path& bundle, const TrustedKeys& trusted,
                          const BundleLimits& limits = {});

// Bundle member names.
inline constexpr const char* kManifestName = "manifest.json";
inline constexpr const char* kSignatureName = "manifest.sig";
inline constexpr const char* kBundleIndexName = "bundle.json";

}  // namespace robodiff::cache
