// The text forms of setting values: parsing what a file or --set gives, printing what
// --print-config shows (config_values.hpp).
#include "config_values.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace robodiff::server::config_values {
namespace {

// A number and a unit suffix: "512KiB" -> (512, "KiB").
bool splitNumber(const std::string& text, double& number, std::string& unit) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  number = std::strtod(begin, &end);
  if (end == begin || errno != 0 || !std::isfinite(number) || number < 0) return false;
  unit = trim(std::string(end));
  return true;
}

std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::uint64_t parseUnsigned(const std::string& value, std::uint64_t max) {
  if (!value.empty() && value.front() == '-') throw std::invalid_argument("is negative");
  if (value.empty() || value.find_first_not_of("0123456789") != std::string::npos)
    throw std::invalid_argument("is not a whole number");
  errno = 0;
  const unsigned long long n = std::strtoull(value.c_str(), nullptr, 10);
  if (errno != 0 || n > max) throw std::invalid_argument("is beyond " + std::to_string(max));
  return n;
}

std::uint64_t parseBytes(const std::string& value) {
  double n = 0;
  std::string unit;
  if (!splitNumber(value, n, unit)) throw std::invalid_argument("is not a size (e.g. 512KiB, 4GiB)");
  double scale = 0;
  if (unit.empty() || unit == "B") scale = 1;
  else if (unit == "KiB" || unit == "K") scale = 1024.0;
  else if (unit == "MiB" || unit == "M") scale = 1024.0 * 1024;
  else if (unit == "GiB" || unit == "G") scale = 1024.0 * 1024 * 1024;
  else if (unit == "KB") scale = 1e3;
  else if (unit == "MB") scale = 1e6;
  else if (unit == "GB") scale = 1e9;
  else throw std::invalid_argument("has unit '" + unit + "'; use B, KiB, MiB, GiB, KB, MB or GB");
  const double bytes = n * scale;
  if (bytes >= 9.2e18) throw std::invalid_argument("is too large");
  return static_cast<std::uint64_t>(std::llround(bytes));
}

std::chrono::milliseconds parseDuration(const std::string& value) {
  double n = 0;
  std::string unit;
  if (!splitNumber(value, n, unit)) throw std::invalid_argument("is not a duration (e.g. 500ms, 30s, 15min)");
  double ms = 0;
  if (unit == "ms") ms = n;
  else if (unit == "s" || unit.empty()) ms = n * 1e3;
  else if (unit == "min") ms = n * 60e3;
  else if (unit == "h") ms = n * 3600e3;
  else throw std::invalid_argument("has unit '" + unit + "'; use ms, s, min or h");
  if (ms >= 9.2e18) throw std::invalid_argument("is too long");
  return std::chrono::milliseconds(static_cast<std::int64_t>(std::llround(ms)));
}

bool parseBool(const std::string& value) {
  if (value == "true" || value == "yes" || value == "on" || value == "1") return true;
  if (value == "false" || value == "no" || value == "off" || value == "0") return false;
  throw std::invalid_argument("is not true or false");
}

std::string formatBytes(std::uint64_t bytes) {
  const char* units[] = {"GiB", "MiB", "KiB"};
  const std::uint64_t scales[] = {std::uint64_t{1} << 30, std::uint64_t{1} << 20, std::uint64_t{1} << 10};
  for (int i = 0; i < 3; ++i)
    if (bytes >= scales[i] && bytes % scales[i] == 0) return std::to_string(bytes / scales[i]) + units[i];
  return std::to_string(bytes) + "B";
}

std::string formatDuration(std::chrono::milliseconds duration) {
  const auto ms = duration.count();
  if (ms % 60000 == 0 && ms != 0) return std::to_string(ms / 60000) + "min";
  if (ms % 1000 == 0) return std::to_string(ms / 1000) + "s";
  return std::to_string(ms) + "ms";
}

std::vector<std::filesystem::path> parseDirectoryList(const std::string& value) {
  std::vector<std::filesystem::path> dirs;
  std::size_t begin = 0;
  while (begin <= value.size()) {
    const std::size_t end = std::min(value.find(':', begin), value.size());
    const std::string dir = trim(value.substr(begin, end - begin));
    if (!dir.empty()) {
      if (dir.front() != '/') throw std::invalid_argument("names '" + dir + "', which is not an absolute path");
      dirs.emplace_back(dir);
    }
    begin = end + 1;
  }
  return dirs;
}

std::string formatDirectoryList(const std::vector<std::filesystem::path>& dirs) {
  std::string text;
  for (const auto& d : dirs) text += (text.empty() ? "" : ":") + d.string();
  return text;
}

namespace {

// "a, b": names whose characters are letters, digits and `extra`; `what` names the kind
// in the error.
std::vector<std::string> splitNames(const std::string& value, std::string_view extra, const char* what) {
  std::vector<std::string> names;
  std::stringstream in(value);
  for (std::string name; std::getline(in, name, ',');) {
    name = trim(name);
    if (name.empty()) continue;
    for (const char ch : name)
      if (!std::isalnum(static_cast<unsigned char>(ch)) && extra.find(ch) == std::string_view::npos)
        throw std::invalid_argument("names '" + name + "', which is not " + what);
    names.push_back(name);
  }
  return names;
}

}  // namespace

std::vector<std::string> parseNameList(const std::string& value) { return splitNames(value, "-.", "a host name"); }

std::vector<std::string> parseServiceNames(const std::string& value) {
  return splitNames(value, "_", "a DDS service name (letters, digits, '_')");
}

std::string formatNameList(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

std::string tomlString(const std::string& text) {
  std::string out = "\"";
  for (const char ch : text) {
    const auto byte = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (byte < 0x20 || byte == 0x7f) {
          char escaped[8];
          std::snprintf(escaped, sizeof escaped, "\\u%04X", byte);
          out += escaped;
        } else {
          out += ch;
        }
    }
  }
  return out + "\"";
}

std::string closestName(const std::string& name, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = 0;
  for (const std::string& candidate : candidates) {
    const std::size_t distance = editDistance(name, candidate);
    const bool contains = name.size() >= 3 && (candidate.find(name) != std::string::npos ||
                                              name.find(candidate) != std::string::npos);
    const bool near = distance <= std::max<std::size_t>(1, std::min(name.size(), candidate.size()) / 3);
    if ((near || contains) && (best.empty() || distance < best_distance)) {
      best = candidate;
      best_distance = distance;
    }
  }
  return best;
}

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

}  // namespace robodiff::server::config_values
