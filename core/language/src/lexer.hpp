// The lexer of the expression language: one token at a time, on demand, so that the
// first error in the text (lexical or syntactic) is the one reported.
#pragma once

#include <cstddef>
#include <string>

namespace robodiff::language::detail {

enum class TokenKind {
  End,        // no more text
  Number,     // `text` the source spelling, `number` its value
  Name,       // `text`
  String,     // `text` the contents, `quote` the quote character
  Symbol,     // one of + - * / @ ^ ( ) [ ] , ; : in `symbol`
  Transpose,  // .T
};

struct Token {
  TokenKind kind = TokenKind::End;
  std::string text;
  double number = 0.0;
  char symbol = 0;
  char quote = 0;
  int column = 1;  // 1-based column of the token's first character
};

// "end of expression", "name 'q'", "number '1e-3'", "')'", ...: for error messages.
std::string describeToken(const Token& token);

// `text`, cut to its first 40 characters (+ "...") so that a huge token cannot make a
// huge message.
std::string shortened(const std::string& text);

// 1-based column of a byte offset, clamped to the range of int.
int columnOf(std::size_t offset);

class Lexer {
 public:
  explicit Lexer(const std::string& text) : text_(text) {}
  // The next token; throws ExpressionError on a malformed number, an unterminated
  // string, a '.' not followed by T or any character outside the language.
  Token next();

 private:
  Token lexNumber();
  Token lexName();
  Token lexString();
  Token lexTranspose();
  void skipWhitespace();
  bool digitAt(std::size_t offset) const;
  // "end of expression", "'$'", "non-ASCII byte 0xC3", ...: the character at an offset.
  std::string describeCharAt(std::size_t offset) const;

  const std::string& text_;
  std::size_t pos_ = 0;
};

}  // namespace robodiff::language::detail
