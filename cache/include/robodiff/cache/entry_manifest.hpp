// The signed description of one cache entry that leaves its host: the entry's key, what
// the index knows of it (model hash, spec, compiler identity and flags, ...), each file's
// name, size and SHA-256, the signer's key id and the signing time. Its canonical JSON
// (sorted keys, compact) is the byte string the signer signs; a receiver verifies the
// signature over the bytes it received, then every received file against the manifest.
//
// File names are "library.so", "description.json" and "src/<name>" (a source as compiled,
// uncompressed), where <name> is a plain file name: no '/', no leading '.', at most 200
// letters, digits and ".-_+".
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "robodiff/cache/artifact_signing.hpp"
#include "robodiff/cache/cache.hpp"

namespace robodiff::cache {

struct ManifestFile {
  std::string name;
  std::uint64_t size = 0;
  std::string sha256;  // lowercase hex
};

struct EntryManifest {
  std::string key;
  EntryInfo info;
  std::vector<ManifestFile> files;  // sorted by name
  std::string signer;               // key id
  std::int64_t signed_at = 0;       // unix seconds
};

// Canonical JSON text of a manifest (the signed bytes).
std::string manifestText(const EntryManifest& manifest);
// Parses and checks a manifest's text: format, fields and types, the key, every file
// name, size and SHA-256. Throws std::runtime_error naming the problem.
EntryManifest parseManifest(const std::string& text);

// Whether `name` may be an entry's file name (see above).
bool isEntryFileName(const std::string& name);

// One entry's files as received (from a bundle, or later over the network): the bytes of
// manifest.json and manifest.sig, and each file's size and SHA-256 as measured on arrival.
struct ReceivedEntry {
  std::string key;  // the key it arrived under (e.g. its directory in a bundle)
  std::optional<std::string> manifest, signature;  // signature: lowercase hex, a newline allowed
  struct File {
    std::uint64_t size = 0;
    std::string sha256;
  };
  std::map<std::string, File> files;
};

// The verified manifest, or a problem naming what is wrong: unsigned (manifest or
// signature missing), a signer not in `trusted`, a bad signature, a manifest for another
// key, a missing or extra file, a size or SHA-256 that differs from the signed one.
struct ManifestCheck {
  std::optional<EntryManifest> manifest;
  std::string problem;
};
ManifestCheck verifyReceivedEntry(const ReceivedEntry& entry, const TrustedKeys& trusted);
// The signature part of that check alone, before any file has arrived: `signature_hex`
// (a newline allowed) by a trusted key over `manifest`, which then parses.
ManifestCheck verifySignedManifest(const std::string& manifest, const std::string& signature_hex,
                                   const TrustedKeys& trusted);

}  // namespace robodiff::cache
