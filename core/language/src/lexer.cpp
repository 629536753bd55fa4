// The lexer: numbers, names, quoted strings, operators and brackets, and .T.
#include "lexer.hpp"

#include <charconv>
#include <climits>
#include <cstdio>
#include <cstring>

#include "robodiff/language/parser.hpp"

namespace robodiff::language::detail {
namespace {

// ASCII classes written out, so that the locale cannot change what a name is.
bool isDigit(char c) { return c >= '0' && c <= '9'; }
bool isNameStart(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool isNameChar(char c) { return isNameStart(c) || isDigit(c); }
bool isWhitespace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

constexpr const char* kSymbols = "+-*/@^()[],;:";
constexpr std::size_t kShownLength = 40;

}  // namespace

std::string shortened(const std::string& text) {
  if (text.size() <= kShownLength) return text;
  return text.substr(0, kShownLength) + "...";
}

int columnOf(std::size_t offset) {
  return offset >= static_cast<std::size_t>(INT_MAX) ? INT_MAX : static_cast<int>(offset + 1);
}

std::string describeToken(const Token& token) {
  switch (token.kind) {
    case TokenKind::End: return "end of expression";
    case TokenKind::Number: return "number '" + shortened(token.text) + "'";
    case TokenKind::Name: return "name '" + shortened(token.text) + "'";
    case TokenKind::String: {
      const std::string quote(1, token.quote);
      return "string " + quote + shortened(token.text) + quote;
    }
    case TokenKind::Symbol: return std::string("'") + token.symbol + "'";
    case TokenKind::Transpose: return "'.T'";
  }
  return "token";
}

std::string Lexer::describeCharAt(std::size_t offset) const {
  if (offset >= text_.size()) return "end of expression";
  const unsigned char c = static_cast<unsigned char>(text_[offset]);
  if (c > 0x20 && c < 0x7f) return std::string("character '") + static_cast<char>(c) + "'";
  if (c == ' ') return "a space";
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(c));
  return (c >= 0x80 ? "non-ASCII byte " : "control character ") + std::string(hex);
}

bool Lexer::digitAt(std::size_t offset) const { return offset < text_.size() && isDigit(text_[offset]); }

void Lexer::skipWhitespace() {
  while (pos_ < text_.size() && isWhitespace(text_[pos_])) ++pos_;
}

Token Lexer::next() {
  skipWhitespace();
  Token token;
  token.column = columnOf(pos_);
  if (pos_ >= text_.size()) return token;  // End
  const char c = text_[pos_];
  if (isDigit(c) || (c == '.' && digitAt(pos_ + 1))) return lexNumber();
  if (isNameStart(c)) return lexName();
  if (c == '\'' || c == '"') return lexString();
  if (c == '.') return lexTranspose();
  if (c != 0 && std::strchr(kSymbols, c) != nullptr) {
    token.kind = TokenKind::Symbol;
    token.symbol = c;
    ++pos_;
    return token;
  }
  throw ExpressionError(token.column, "expected a number, name, string, operator or bracket, found " +
                                          describeCharAt(pos_));
}

// digits ['.' digits] [('e' | 'E') ['+' | '-'] digits], or '.' digits [exponent]. The
// number must not run into a '.', a letter or '_' ("1..2", "12abc", "2.T").
Token Lexer::lexNumber() {
  const std::size_t start = pos_;
  const auto malformed = [&](const std::string& expected) {
    return ExpressionError(columnOf(pos_), "malformed number starting at column " +
                                               std::to_string(columnOf(start)) + ": expected " + expected +
                                               " after '" + shortened(text_.substr(start, pos_ - start)) +
                                               "', found " + describeCharAt(pos_));
  };
  while (digitAt(pos_)) ++pos_;
  if (pos_ < text_.size() && text_[pos_] == '.') {
    ++pos_;
    while (digitAt(pos_)) ++pos_;
  }
  if (pos_ < text_.size() && (text_[pos_] == 'e' || text_[pos_] == 'E')) {
    ++pos_;
    if (pos_ < text_.size() && (text_[pos_] == '+' || text_[pos_] == '-')) ++pos_;
    if (!digitAt(pos_)) throw malformed("the digits of the exponent");
    while (digitAt(pos_)) ++pos_;
  }
  if (pos_ < text_.size() && (text_[pos_] == '.' || isNameChar(text_[pos_]))) {
    throw malformed("a digit, an exponent or an operator");
  }
  Token token;
  token.kind = TokenKind::Number;
  token.column = columnOf(start);
  token.text = text_.substr(start, pos_ - start);
  const char* first = text_.data() + start;
  const auto [end, error] = std::from_chars(first, text_.data() + pos_, token.number);
  if (error != std::errc() || end != text_.data() + pos_) {
    throw ExpressionError(token.column, "expected a number within the range of a double, found number '" +
                                            shortened(token.text) + "'");
  }
  return token;
}

Token Lexer::lexName() {
  Token token;
  token.kind = TokenKind::Name;
  token.column = columnOf(pos_);
  const std::size_t start = pos_;
  while (pos_ < text_.size() && isNameChar(text_[pos_])) ++pos_;
  token.text = text_.substr(start, pos_ - start);
  return token;
}

// 'text' or "text", without escapes; the contents run to the next matching quote.
Token Lexer::lexString() {
  Token token;
  token.kind = TokenKind::String;
  token.column = columnOf(pos_);
  token.quote = text_[pos_];
  const std::size_t close = text_.find(token.quote, pos_ + 1);
  if (close == std::string::npos) {
    throw ExpressionError(token.column, std::string("unterminated string: expected a closing ") + token.quote +
                                            " for the string opened at column " +
                                            std::to_string(token.column) + ", found end of expression");
  }
  token.text = text_.substr(pos_ + 1, close - pos_ - 1);
  pos_ = close + 1;
  return token;
}

// '.' is only the start of .T (a '.' before a digit starts a number instead).
Token Lexer::lexTranspose() {
  Token token;
  token.kind = TokenKind::Transpose;
  token.column = columnOf(pos_);
  const std::size_t after = pos_ + 1;
  std::size_t name_end = after;
  while (name_end < text_.size() && isNameChar(text_[name_end])) ++name_end;
  if (name_end == after + 1 && text_[after] == 'T') {
    pos_ = name_end;
    return token;
  }
  const std::string found = name_end > after ? "'" + shortened(text_.substr(after, name_end - after)) + "'"
                                             : describeCharAt(after);
  throw ExpressionError(columnOf(after), "expected 'T' after '.' (the transpose x.T), found " + found);
}

}  // namespace robodiff::language::detail
