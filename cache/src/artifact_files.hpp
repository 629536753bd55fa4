// File operations the cache relies on for durability and integrity: copies that are
// fsynced before they count, zstd-compressed copies of sources, SHA-256 of a file,
// directory sizes. Errors throw CacheError(Io) naming the file and the reason.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace robodiff::cache::detail {

// Copies `from` to `to` (created with `mode`), fsynced.
void copyFileSynced(const std::filesystem::path& from, const std::filesystem::path& to, unsigned mode);
// Writes `from` zstd-compressed to `to` (mode 0600), fsynced.
void compressFileSynced(const std::filesystem::path& from, const std::filesystem::path& to);
// Writes `text` to `to` (mode 0600), fsynced.
void writeFileSynced(const std::filesystem::path& to, const std::string& text);
// The decompressed bytes of a file written by compressFileSynced.
std::string decompressFile(const std::filesystem::path& path);

void fsyncDirectory(const std::filesystem::path& dir);

// Lowercase hex SHA-256 of the file's bytes.
std::string sha256OfFile(const std::filesystem::path& path);

// Total size of the regular files under dir (0 when it does not exist).
std::uint64_t directoryBytes(const std::filesystem::path& dir);

// Removes a tree, ignoring errors (used when cleaning up after a failure).
void removeTreeQuietly(const std::filesystem::path& path) noexcept;

}  // namespace robodiff::cache::detail
