#include "utf8_check.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>

#include "robodiff/model/model_error.hpp"

namespace robodiff::detail {
namespace {

// The length of the valid UTF-8 sequence starting at text[i], or 0 if there is none.
std::size_t sequenceLength(const std::string& text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<std::uint8_t>(text[k]); };
  const std::uint8_t lead = byte(i);
  if (lead < 0x80) return 1;
  std::size_t length = 0;
  std::uint8_t low = 0x80, high = 0xBF;  // the second byte's range (RFC 3629's table)
  if (lead >= 0xC2 && lead <= 0xDF) length = 2;
  else if (lead == 0xE0) length = 3, low = 0xA0;
  else if (lead >= 0xE1 && lead <= 0xEC) length = 3;
  else if (lead == 0xED) length = 3, high = 0x9F;
  else if (lead >= 0xEE && lead <= 0xEF) length = 3;
  else if (lead == 0xF0) length = 4, low = 0x90;
  else if (lead >= 0xF1 && lead <= 0xF3) length = 4;
  else if (lead == 0xF4) length = 4, high = 0x8F;
  else return 0;
  if (i + length > text.size()) return 0;
  if (byte(i + 1) < low || byte(i + 1) > high) return 0;
  for (std::size_t k = 2; k < length; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return length;
}

[[noreturn]] void refuse(const std::string& text, std::size_t i, const std::string& source, const char* what) {
  const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(i), '\n');
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(static_cast<std::uint8_t>(text[i])));
  throw ModelError(source + ":" + std::to_string(line) + ": " + what + " (byte " + hex + " at offset " +
                   std::to_string(i) + "); the URDF must be UTF-8 text");
}

}  // namespace

void checkUtf8(const std::string& text, const std::string& source) {
  for (std::size_t i = 0; i < text.size();) {
    if (text[i] == '\0') refuse(text, i, source, "a NUL byte");
    const std::size_t length = sequenceLength(text, i);
    if (length == 0) refuse(text, i, source, "not valid UTF-8");
    i += length;
  }
}

}  // namespace robodiff::detail
