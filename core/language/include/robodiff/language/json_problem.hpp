// A JSON parser's error, said for a person: "line 3, column 1: unexpected end of input;
// expected ']'" instead of nlohmann's "[json.exception.parse_error.101] parse error at
// line 3, column 1: syntax error while parsing array - ...". Works on the message text,
// so this layer needs no JSON library.
#pragma once

#include <string>

namespace robodiff::language {

// The problem in `parser_message` (an exception's what()), without the library's codes
// and jargon; the message unchanged when it is not one of nlohmann's parse errors.
std::string jsonProblem(const std::string& parser_message);

}  // namespace robodiff::language
