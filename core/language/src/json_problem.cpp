#include "robodiff/language/json_problem.hpp"

#include <regex>

#include "robodiff/language/bounded_text.hpp"

namespace robodiff::language {

// libstdc++'s std::regex recurses once per character matched: a message quoting a 200 KB
// unterminated string (nlohmann's "last read: '...'") overflowed the stack of robodiffd's
// GetFunction (found by tests/fuzz/spec_fuzz.cpp). Messages are cut first, like any
// client-sent text quoted in a message.
constexpr std::size_t kMaxMessageBytes = 1024;

std::string jsonProblem(const std::string& full_message) {
  const std::string parser_message =
      full_message.size() > kMaxMessageBytes ? boundedText(full_message, kMaxMessageBytes) : full_message;
  // [json.exception.parse_error.101] parse error at line 3, column 1: syntax error while
  // parsing array - unexpected end of input; expected ']'
  static const std::regex parse_error(
      R"(\[json\.exception\.[a-z_]+\.\d+\] (?:parse error(?: at (line \d+, column \d+|byte \d+))?: )?(?:syntax error while parsing ([a-z ]+?) - )?([\s\S]*))");
  std::smatch m;
  if (!std::regex_match(parser_message, m, parse_error)) return parser_message;
  std::string out;
  if (m[1].matched) out = m[1].str() + ": ";
  out += m[3].str();
  if (m[2].matched) out += " (in " + std::string(m[2].str() == "value" ? "a value" : "an " + m[2].str()) + ")";
  return out;
}

}  // namespace robodiff::language
