#include "output/human_units.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace robodiff::cli {

std::string formatBytes(std::uint64_t bytes) {
  static const char* units[] = {"KiB", "MiB", "GiB", "TiB", "PiB"};
  if (bytes < 1024) return std::to_string(bytes) + " B";
  double value = static_cast<double>(bytes) / 1024.0;
  int unit = 0;
  while (value >= 1024.0 && unit < 4) {
    value /= 1024.0;
    ++unit;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f %s", value, units[unit]);
  return buf;
}

std::uint64_t parseSize(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return std::invalid_argument("'" + text + "' is not a size (" + why + "; e.g. 1048576, 500M, 2G, 1.5GiB, 800MB)");
  };
  std::size_t i = 0;
  while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
  const std::size_t number_begin = i;
  while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.')) ++i;
  const std::string number = text.substr(number_begin, i - number_begin);
  if (number.empty() || number.front() == '.' || std::count(number.begin(), number.end(), '.') > 1)
    throw bad("it does not start with a number");
  while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
  std::string unit;
  for (; i < text.size(); ++i) {
    if (std::isspace(static_cast<unsigned char>(text[i]))) break;
    unit += static_cast<char>(std::tolower(static_cast<unsigned char>(text[i])));
  }
  while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
  if (i != text.size()) throw bad("unexpected text after the unit");

  // Binary prefixes unless the unit spells the SI form ("MB").
  static const std::pair<const char*, double> units[] = {
      {"", 1.0},       {"b", 1.0},     {"k", 0x1p10},   {"ki", 0x1p10}, {"kib", 0x1p10}, {"kb", 1e3},
      {"m", 0x1p20},   {"mi", 0x1p20}, {"mib", 0x1p20}, {"mb", 1e6},    {"g", 0x1p30},   {"gi", 0x1p30},
      {"gib", 0x1p30}, {"gb", 1e9},    {"t", 0x1p40},   {"ti", 0x1p40}, {"tib", 0x1p40}, {"tb", 1e12},
  };
  double multiplier = 0;
  for (const auto& [name, value] : units)
    if (unit == name) multiplier = value;
  if (multiplier == 0) throw bad("unknown unit '" + unit + "'");
  const double bytes = std::strtod(number.c_str(), nullptr) * multiplier;
  if (!std::isfinite(bytes) || bytes >= 0x1p64) throw bad("too large");
  if (multiplier == 1.0 && bytes != std::floor(bytes)) throw bad("a byte count is a whole number");
  return static_cast<std::uint64_t>(std::round(bytes));
}

std::string formatAge(std::int64_t seconds) {
  seconds = std::max<std::int64_t>(seconds, 0);
  if (seconds < 60) return std::to_string(seconds) + " s";
  if (seconds < 3600) return std::to_string(seconds / 60) + " min";
  if (seconds < 86400) return std::to_string(seconds / 3600) + " h";
  return std::to_string(seconds / 86400) + " d";
}

std::string formatClock(double seconds) {
  const long total = std::lround(std::max(seconds, 0.0));
  char buf[32];
  if (total >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", total / 3600, total / 60 % 60, total % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", total / 60, total % 60);
  return buf;
}

std::string formatFixed(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
}

std::string formatGrouped(double x) {
  const std::string digits = std::to_string(static_cast<std::uint64_t>(x + 0.5));
  std::string out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

}  // namespace robodiff::cli
