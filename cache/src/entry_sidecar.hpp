// entry.json: the part of an index row that the object files cannot tell, written next
// to library.so when an artifact is published (inside the artifact's directory before
// it is renamed into place, so it is there exactly when the artifact is). `cache repair`
// re-creates a lost index row from it and checks the library against its SHA-256.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "robodiff/cache/cache.hpp"

namespace robodiff::cache::detail {

inline constexpr const char* kSidecarName = "entry.json";

// The sidecar's text for a ready entry (key, info, library size and SHA-256, created).
std::string sidecarText(const Entry& entry);

// The entry a sidecar describes (state "ready", hits 0, total_bytes 0: the caller measures
// the directory). Throws std::runtime_error naming the file and the field when it is
// unreadable, malformed or lacks a field.
Entry readSidecar(const std::filesystem::path& file);

}  // namespace robodiff::cache::detail
