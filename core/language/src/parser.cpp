// The parser: recursive descent over the lexer's tokens, one token of lookahead, no
// backtracking (so linear time). Operator chains are loops; every recursion into a nested
// construct first takes a nesting level (Nested), which fails before the stack grows past
// ParseLimits::max_depth levels.
#include "robodiff/language/parser.hpp"

#include <algorithm>
#include <utility>

#include "lexer.hpp"

namespace robodiff::language {

ExpressionError::ExpressionError(int column, const std::string& message)
    : std::runtime_error("column " + std::to_string(column) + ": " + message), column_(column), message_(message) {}

namespace {

using detail::Token;
using detail::TokenKind;

class Parser {
 public:
  Parser(const std::string& text, const ParseLimits& limits) : lexer_(text), limits_(limits) { advance(); }

  ExprPtr parseAll() {
    ExprPtr expr = parseInner("an expression");
    if (tok_.kind != TokenKind::End) failTrailing();
    return expr;
  }

 private:
  // One nesting level for as long as it lives; throws before entering one too many.
  class Nested {
   public:
    Nested(Parser& parser, int column) : parser_(parser) {
      if (parser_.depth_ >= parser_.limits_.max_depth) {
        throw ExpressionTooLarge(column, "the expression nests deeper than the limit of " +
                                             std::to_string(parser_.limits_.max_depth) +
                                             " levels (parentheses, calls, brackets, unary operators and "
                                             "exponents)");
      }
      ++parser_.depth_;
    }
    ~Nested() { --parser_.depth_; }
    Nested(const Nested&) = delete;
    Nested& operator=(const Nested&) = delete;

   private:
    Parser& parser_;
  };

  void advance() { tok_ = lexer_.next(); }
  bool isSymbol(char c) const { return tok_.kind == TokenKind::Symbol && tok_.symbol == c; }
  static std::string quoted(const std::string& text) { return "'" + detail::shortened(text) + "'"; }

  // "expected <expected>, found <the current token>" at the given column.
  [[noreturn]] void fail(int column, const std::string& expected) const {
    throw ExpressionError(column, "expected " + expected + ", found " + detail::describeToken(tok_));
  }
  [[noreturn]] void fail(const std::string& expected) const { fail(tok_.column, expected); }

  // A new node; counts it against max_nodes.
  std::shared_ptr<Expr> make(ExprKind kind, int column) {
    if (++nodes_ > limits_.max_nodes) {
      throw ExpressionTooLarge(tok_.column, "the expression has more nodes than the limit of " +
                                                std::to_string(limits_.max_nodes));
    }
    auto node = std::make_shared<Expr>();
    node->kind = kind;
    node->column = column;
    return node;
  }

  ExprPtr binary(const Token& op, ExprPtr left, ExprPtr right, int column) {
    auto node = make(ExprKind::Binary, column);
    node->text = std::string(1, op.symbol);
    node->args = {std::move(left), std::move(right)};
    return node;
  }

  // Whether the current token can begin an operand (a number, name, string, '(', '[',
  // or a unary sign).
  bool startsOperand() const {
    switch (tok_.kind) {
      case TokenKind::Number:
      case TokenKind::Name:
      case TokenKind::String: return true;
      case TokenKind::Symbol: return tok_.symbol == '(' || tok_.symbol == '[' || tok_.symbol == '-' || tok_.symbol == '+';
      default: return false;
    }
  }

  // Consumes an operator and checks that an operand follows it; a missing operand is
  // reported at the operator.
  Token takeOperator() {
    Token op = tok_;
    advance();
    if (!startsOperand()) fail(op.column, "an operand after " + detail::describeToken(op));
    return op;
  }

  // A full expression where `what` is expected (inside brackets, at the top level).
  ExprPtr parseInner(const std::string& what) {
    if (!startsOperand()) fail(what);
    return parseSum();
  }

  ExprPtr parseSum() {
    const int start = tok_.column;
    ExprPtr left = parseProduct();
    while (isSymbol('+') || isSymbol('-')) {
      const Token op = takeOperator();
      left = binary(op, std::move(left), parseProduct(), start);
    }
    return left;
  }

  ExprPtr parseProduct() {
    const int start = tok_.column;
    ExprPtr left = parseUnary();
    while (isSymbol('*') || isSymbol('/') || isSymbol('@')) {
      const Token op = takeOperator();
      left = binary(op, std::move(left), parseUnary(), start);
    }
    return left;
  }

  ExprPtr parseUnary() {
    if (!isSymbol('-') && !isSymbol('+')) return parsePower();
    const Token op = takeOperator();
    Nested nested(*this, op.column);
    ExprPtr operand = parseUnary();
    if (op.symbol == '+') return operand;  // unary plus changes nothing
    auto node = make(ExprKind::Unary, op.column);
    node->text = "-";
    node->args = {std::move(operand)};
    return node;
  }

  // The exponent is a unary (2^-1) and recursion makes '^' right associative.
  ExprPtr parsePower() {
    const int start = tok_.column;
    ExprPtr base = parsePostfix();
    if (!isSymbol('^')) return base;
    const Token op = takeOperator();
    Nested nested(*this, op.column);
    return binary(op, std::move(base), parseUnary(), start);
  }

  ExprPtr parsePostfix() {
    const int start = tok_.column;
    ExprPtr node = parsePrimary();
    for (;;) {
      if (isSymbol('[')) {
        node = parseIndex(std::move(node), start);
      } else if (tok_.kind == TokenKind::Transpose) {
        auto transpose = make(ExprKind::Transpose, start);
        transpose->args = {std::move(node)};
        node = std::move(transpose);
        advance();
      } else if (isSymbol('(')) {
        fail("an operator (only a name can be called, as in f(x))");
      } else {
        return node;
      }
    }
  }

  ExprPtr parsePrimary() {
    switch (tok_.kind) {
      case TokenKind::Number: return leaf(ExprKind::Number);
      case TokenKind::String: return leaf(ExprKind::String);
      case TokenKind::Name: {
        const Token name = tok_;
        advance();
        if (isSymbol('(')) return parseCall(name);
        auto node = make(ExprKind::Name, name.column);
        node->text = name.text;
        return node;
      }
      case TokenKind::Symbol:
        if (isSymbol('(')) return parseParenthesised();
        if (isSymbol('[')) return parseMatrix();
        break;
      default: break;
    }
    fail("an operand (a number, name, string, '(' or '[')");
  }

  // A number or string from the current token.
  ExprPtr leaf(ExprKind kind) {
    auto node = make(kind, tok_.column);
    node->number = tok_.number;
    if (kind == ExprKind::String) node->text = tok_.text;
    advance();
    return node;
  }

  // `close` after a bracketed construct, or an error naming where it was opened.
  void expectClose(char close, const Token& open, const std::string& what) {
    if (!isSymbol(close)) {
      fail(std::string("'") + close + "' to close " + what + " opened at column " + std::to_string(open.column));
    }
    advance();
  }

  ExprPtr parseParenthesised() {
    const Token open = tok_;
    advance();
    Nested nested(*this, open.column);
    ExprPtr inner = parseInner("an expression inside the parenthesis opened at column " + std::to_string(open.column));
    expectClose(')', open, "the parenthesis");
    return inner;
  }

  ExprPtr parseCall(const Token& name) {
    const Token open = tok_;
    advance();
    Nested nested(*this, open.column);
    auto node = make(ExprKind::Call, name.column);
    node->text = name.text;
    const std::string call = "the call of " + quoted(name.text) + " opened at column " + std::to_string(name.column);
    if (isSymbol(')')) {
      advance();
      return node;
    }
    for (;;) {
      node->args.push_back(parseInner("an argument of " + quoted(name.text)));
      if (isSymbol(',')) {
        advance();
      } else if (isSymbol(')')) {
        advance();
        return node;
      } else {
        fail((tok_.kind == TokenKind::End ? "')' to close " : "',' or ')' to close ") + call);
      }
    }
  }

  // [a, b; c, d]: ',' puts elements side by side, ';' starts the next row.
  ExprPtr parseMatrix() {
    const Token open = tok_;
    advance();
    Nested nested(*this, open.column);
    auto node = make(ExprKind::Matrix, open.column);
    node->rows.emplace_back();
    for (;;) {
      node->rows.back().push_back(parseInner("a matrix element (empty matrices, rows and elements are not allowed)"));
      if (isSymbol(',')) {
        advance();
      } else if (isSymbol(';')) {
        advance();
        node->rows.emplace_back();
      } else if (isSymbol(']')) {
        advance();
        return node;
      } else {
        fail("',', ';' or ']' to close the matrix opened at column " + std::to_string(open.column));
      }
    }
  }

  // x[range] or x[range, range]; `start` is the column where x begins.
  ExprPtr parseIndex(ExprPtr base, int start) {
    const Token open = tok_;
    advance();
    Nested nested(*this, open.column);
    auto node = make(ExprKind::Index, start);
    node->args = {std::move(base)};
    const std::string index = "the index opened at column " + std::to_string(open.column);
    for (;;) {
      node->ranges.push_back(parseRange());
      if (isSymbol(']')) {
        advance();
        return node;
      }
      const bool second = node->ranges.size() == 2;
      if (isSymbol(',') && !second) {
        advance();
        continue;
      }
      const bool slice = node->ranges.back().is_slice;
      if (second) fail((slice ? "']'" : "':' or ']'") + (" to close " + index) + " (at most two ranges: rows, columns)");
      fail((slice ? "',' or ']'" : "':', ',' or ']'") + (" to close " + index));
    }
  }

  // i, i:j, :j, i:, or :
  IndexRange parseRange() {
    IndexRange range;
    if (!isSymbol(':')) {
      range.begin = parseInner("an index or a slice");
      if (!isSymbol(':')) return range;
    }
    range.is_slice = true;
    advance();
    if (!isSymbol(',') && !isSymbol(']')) range.end = parseInner("the end of the slice, ',' or ']'");
    return range;
  }

  [[noreturn]] void failTrailing() const {
    if (isSymbol(')') || isSymbol(']')) {
      fail(std::string("an operator or the end of the expression (this '") + tok_.symbol + "' closes nothing)");
    }
    fail("an operator or the end of the expression");
  }

  detail::Lexer lexer_;
  const ParseLimits& limits_;
  Token tok_;
  int depth_ = 0;
  std::size_t nodes_ = 0;
};

}  // namespace

ExprPtr parseExpression(const std::string& text, const ParseLimits& limits) {
  if (text.size() > limits.max_length) {
    throw ExpressionTooLarge(detail::columnOf(limits.max_length),
                             "the expression is " + std::to_string(text.size()) +
                                 " characters long, more than the limit of " + std::to_string(limits.max_length) +
                                 " characters");
  }
  return Parser(text, limits).parseAll();
}

std::string caretLine(const std::string& text, int column) {
  if (text.size() > 200 || text.find('\n') != std::string::npos) return "";
  return "\n    " + text + "\n    " + std::string(static_cast<std::size_t>(std::max(column, 1) - 1), ' ') + "^";
}

}  // namespace robodiff::language
