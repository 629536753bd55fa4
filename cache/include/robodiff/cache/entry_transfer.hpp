// One cache entry leaving its host and arriving at another, whatever carries it (a tar
// bundle, artifact_bundle.hpp; a fleet's DDS transfer, issue 23): the sender signs the
// entry's manifest (entry_manifest.hpp) and sends its files concatenated in the
// manifest's order (the "payload"); the receiver checks the signature before it takes a
// byte, stores the payload in a private scratch directory outside the cache, hashing each
// file on the way, and files the entry through claim/publish only when every file's size
// and SHA-256 are the signed ones, so nothing partial or unverified reaches the cache.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/entry_manifest.hpp"

namespace robodiff::cache {

// One file of an entry, in memory: what is hashed is what is sent.
struct EntryFile {
  std::string name;  // "library.so", "description.json", "src/<name>" (isEntryFileName)
  std::string bytes;
};

// An entry ready to send: its signed manifest and the files it lists, in its order.
struct SignedEntry {
  std::string key;
  std::string manifest;       // canonical JSON text: the signed bytes
  std::string signature_hex;  // 128 lowercase hex digits
  std::vector<EntryFile> files;

  // The files' sizes added up.
  std::uint64_t payloadBytes() const;
  // Copies payload bytes [offset, offset + max_bytes) to `out` (resized to what there is;
  // empty when offset is at or past the end).
  void readPayload(std::uint64_t offset, std::size_t max_bytes, std::vector<std::uint8_t>& out) const;
};

// The verified artifact for key, or std::runtime_error saying why there is none (absent,
// still being built, or failed verification and moved to quarantine).
Artifact exportableArtifact(Cache& cache, const std::string& key);
// The files of a verified artifact, sorted by name: description.json, library.so, then
// (include_sources) its sources decompressed, the C as compiled, independent of the zstd
// version. Throws std::runtime_error for a source whose name cannot travel.
std::vector<EntryFile> entryFiles(const Artifact& artifact, bool include_sources);
// The artifact's files and their manifest signed by `signer` at `signed_at` (unix seconds).
SignedEntry signEntry(const Artifact& artifact, const SigningKey& signer, bool include_sources,
                      std::int64_t signed_at);

// What became of one received entry.
struct ImportResult {
  enum class Status : std::uint8_t { Imported, Present, Refused };
  std::string key;  // as it arrived (a bundle's directory), or a member's name when it had none
  Status status = Status::Refused;
  std::string robot, function;  // from the signed manifest (empty when refused before it was trusted)
  std::string signer;           // key id, when verified
  std::string problem;          // Refused: what was wrong
};

// Files a verified entry whose files are in `dir` (library.so, description.json, src/...)
// through claim/publish: Imported; Present when it is there already (left alone); Refused
// with the problem when another process is building it (after waiting up to 30 s) or it
// could not be filed.
ImportResult installVerifiedEntry(Cache& cache, const EntryManifest& manifest, const std::filesystem::path& dir);

// What was wrong with what arrived: unsigned, unknown signer, bad signature, another key,
// over the limits, too many bytes, incomplete, a file that differs from the signed one.
class TransferRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TransferLimits {
  std::uint64_t max_payload_bytes = std::uint64_t{1} << 30;
  std::uint64_t max_manifest_bytes = std::uint64_t{1} << 20;
  std::uint64_t max_files = 4096;
};

// Receives one signed entry's payload, in order, into a private scratch directory
// (removed with the receiver).
class EntryReceiver {
 public:
  // Checks the manifest's size, its signature against `trusted` and its content
  // (parseManifest) before any byte is taken; `expected_key` non-empty: the manifest must
  // be for that key. Throws TransferRefused naming the problem (unsigned, unknown signer,
  // bad signature, another key, over the limits), CacheError(Io) when the scratch
  // directory cannot be made.
  EntryReceiver(const std::string& manifest, const std::string& signature_hex, const TrustedKeys& trusted,
                const std::string& expected_key, const TransferLimits& limits = {});
  ~EntryReceiver();
  EntryReceiver(EntryReceiver&&) noexcept;
  EntryReceiver& operator=(EntryReceiver&&) noexcept;

  const EntryManifest& manifest() const;
  std::uint64_t payloadBytes() const;  // the manifest's file sizes added up
  std::uint64_t received() const;
  bool complete() const { return received() == payloadBytes(); }

  // The next bytes of the payload, split into the manifest's files and hashed on the
  // way. Throws TransferRefused (taking none of them) when they go past the end of the
  // payload; CacheError(Io) when the scratch directory cannot be written (then install()
  // refuses).
  void append(const std::uint8_t* data, std::size_t size);

  // Checks each file's size and SHA-256 against the signed ones (verifyReceivedEntry),
  // then files the entry (installVerifiedEntry): Imported or Present, or Refused for what
  // the cache could not take (busy, unwritable). Throws TransferRefused naming the problem
  // when the payload is incomplete or a file differs; nothing partial reaches the cache.
  ImportResult install(Cache& cache);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace robodiff::cache
