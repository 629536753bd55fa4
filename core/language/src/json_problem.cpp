#include "robodiff/language/json_problem.hpp"

#include <regex>

namespace robodiff::language {

std::string jsonProblem(const std::string& parser_message) {
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
