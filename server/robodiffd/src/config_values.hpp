#pragma once
// The text forms of robodiffd's setting values, shared by the config file reader, --set
// and --print-config: sizes (512KiB), durations (30s), counts, flags, lists, and TOML's
// quoting of strings. Every parser throws std::invalid_argument saying what is wrong, in
// words that follow "key = 'value'" ("is not a whole number").

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace robodiff::server::config_values {

std::string trim(const std::string& s);

// Decimal digits only, at most `max`.
std::uint64_t parseUnsigned(const std::string& value, std::uint64_t max);
// A number and a unit: B, KiB, MiB, GiB (K, M, G), KB, MB, GB; no unit: bytes.
std::uint64_t parseBytes(const std::string& value);
// A number and a unit: ms, s, min, h; no unit: seconds.
std::chrono::milliseconds parseDuration(const std::string& value);
// true/yes/on/1, false/no/off/0 (the words --set takes; a file uses TOML's true / false).
bool parseBool(const std::string& value);

// The largest unit that divides exactly: 1048576 -> "1MiB", 1000 -> "1000B".
std::string formatBytes(std::uint64_t bytes);
// 900000 ms -> "15min", 90000 -> "90s", 250 -> "250ms".
std::string formatDuration(std::chrono::milliseconds duration);

// "dir1:dir2" (as PATH is written): absolute directories only.
std::vector<std::filesystem::path> parseDirectoryList(const std::string& value);
std::string formatDirectoryList(const std::vector<std::filesystem::path>& dirs);
// "a, b": host names (letters, digits, '-', '.').
std::vector<std::string> parseNameList(const std::string& value);
std::string formatNameList(const std::vector<std::string>& names);
// "build_a, build_b": DDS service names (letters, digits, '_'; topics are "<name>_request").
std::vector<std::string> parseServiceNames(const std::string& value);

// A TOML basic string: "..." with '"', '\' and control characters escaped.
std::string tomlString(const std::string& text);

// The candidate nearest to `name` (edit distance, or one containing the other); "" when
// none is near enough to be a likely typo.
std::string closestName(const std::string& name, const std::vector<std::string>& candidates);
// "a, b, c": names listed for an error.
std::string joined(const std::vector<std::string>& names);

}  // namespace robodiff::server::config_values
