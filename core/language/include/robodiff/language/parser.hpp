// The parser of the expression language: text -> syntax tree (expression.hpp).
//
//   sum      := product (('+' | '-') product)*            left associative, lowest
//   product  := unary (('*' | '/' | '@') unary)*          left associative
//   unary    := ('-' | '+') unary | power                 -x^2 is -(x^2)
//   power    := postfix ('^' unary)?                      right associative: a^b^c is a^(b^c)
//   postfix  := primary ('[' ranges ']' | '.T')*          x[0:3].T, f(x)[2], (a@b).T
//   primary  := number | string | name | name '(' args? ')' | '(' sum ')' | '[' rows ']'
//   ranges   := range (',' range)?                        rows, then columns
//   range    := sum | sum? ':' sum?                       x[i], x[i:j], x[:j], x[i:], x[:]
//   rows     := row (';' row)*,  row := sum (',' sum)*    [a, b; c, d]
//
// Unary plus is dropped (+x parses to x); unary minus is always a Unary node, also on a
// number literal. Whitespace is space, tab, carriage return and newline. Columns count
// bytes from the start of the text (a newline does not restart them), from 1.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

#include "robodiff/language/expression.hpp"

namespace robodiff::language {

// Bounds on the input, so that hostile text cannot exhaust the stack, memory or time.
// max_depth bounds the nesting of parentheses, calls, brackets, unary operators and
// exponents; it is checked before every recursion. Operator chains (a + b + c ...) are
// parsed by loops, not recursion, so they are bounded only by max_nodes; their trees are
// left-deep, so a tree can be up to about max_nodes / 2 deep.
struct ParseLimits {
  std::size_t max_length = 65536;  // characters (bytes) of text
  int max_depth = 64;              // nesting levels
  std::size_t max_nodes = 20000;   // Expr nodes in the tree
};

// A syntax error. what() is "column N: <message>"; message() is the bare message, which
// says what was expected and what was found.
class ExpressionError : public std::runtime_error {
 public:
  ExpressionError(int column, const std::string& message);
  int column() const { return column_; }  // 1-based
  const std::string& message() const { return message_; }

 private:
  int column_;
  std::string message_;
};

// The text exceeds one of the ParseLimits; the message names the limit and its value.
class ExpressionTooLarge : public ExpressionError {
 public:
  using ExpressionError::ExpressionError;
};

// Parses one whole expression; throws ExpressionError (or ExpressionTooLarge) on the
// first problem. Time and memory are linear in the length of the text.
ExprPtr parseExpression(const std::string& text, const ParseLimits& limits = {});

// The text and a caret under `column`, indented, for an error message ("" for text too
// long or spanning lines to show that way).
std::string caretLine(const std::string& text, int column);

}  // namespace robodiff::language
