#include "robodiff/language/bounded_text.hpp"

namespace robodiff::language {
namespace {

// A cut at `at` that does not split a UTF-8 character (continuation bytes are 10xxxxxx).
std::size_t characterBoundary(std::string_view text, std::size_t at) {
  while (at > 0 && (static_cast<unsigned char>(text[at]) & 0xC0) == 0x80) --at;
  return at;
}

}  // namespace

std::string boundedText(std::string_view text, std::size_t max_bytes) {
  if (text.size() <= max_bytes) return std::string(text);
  std::string out(text.substr(0, characterBoundary(text, max_bytes)));
  out += "\u2026 (" + std::to_string(text.size()) + " bytes)";
  return out;
}

std::string quote(std::string_view text, std::size_t max_bytes) {
  return "'" + boundedText(text, max_bytes) + "'";
}

}  // namespace robodiff::language
