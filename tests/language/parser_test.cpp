// The expression parser: tree shapes (precedence, associativity, every construct, shown
// by a small printer), node columns, errors (column and message) and the limits against
// hostile input (deep nesting, long text, many nodes).
#include <chrono>
#include <sstream>

#include <gtest/gtest.h>

#include "robodiff/language/parser.hpp"

namespace robodiff::language {
namespace {

std::string show(const ExprPtr& e);

std::string showList(const std::vector<ExprPtr>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + show(items[i]);
  return out;
}

std::string showRange(const IndexRange& range) {
  std::string out = range.begin ? show(range.begin) : "";
  if (range.is_slice) out += ":" + (range.end ? show(range.end) : "");
  return out;
}

// Binary and unary nodes are fully parenthesised, so the printed text is the tree's shape.
std::string show(const ExprPtr& e) {
  switch (e->kind) {
    case ExprKind::Number: {
      std::ostringstream s;
      s << e->number;
      return s.str();
    }
    case ExprKind::String: return "'" + e->text + "'";
    case ExprKind::Name: return e->text;
    case ExprKind::Call: return e->text + "(" + showList(e->args) + ")";
    case ExprKind::Unary: return "(" + e->text + show(e->args.at(0)) + ")";
    case ExprKind::Binary: return "(" + show(e->args.at(0)) + " " + e->text + " " + show(e->args.at(1)) + ")";
    case ExprKind::Matrix: {
      std::string out = "[";
      for (std::size_t r = 0; r < e->rows.size(); ++r) out += (r ? "; " : "") + showList(e->rows[r]);
      return out + "]";
    }
    case ExprKind::Index: {
      std::string out = show(e->args.at(0)) + "[";
      for (std::size_t r = 0; r < e->ranges.size(); ++r) out += (r ? ", " : "") + showRange(e->ranges[r]);
      return out + "]";
    }
    case ExprKind::Transpose: return show(e->args.at(0)) + ".T";
  }
  return "?";
}

std::string parsed(const std::string& text) { return show(parseExpression(text)); }

TEST(Parser, PrecedenceAndAssociativity) {
  EXPECT_EQ(parsed("a + b * c"), "(a + (b * c))");
  EXPECT_EQ(parsed("a * b + c"), "((a * b) + c)");
  EXPECT_EQ(parsed("a - b - c"), "((a - b) - c)");
  EXPECT_EQ(parsed("a - b + c"), "((a - b) + c)");
  EXPECT_EQ(parsed("a / b * c"), "((a / b) * c)");
  EXPECT_EQ(parsed("a @ b * c / d"), "(((a @ b) * c) / d)");
  EXPECT_EQ(parsed("a ^ b ^ c"), "(a ^ (b ^ c))");
  EXPECT_EQ(parsed("a * b ^ c"), "(a * (b ^ c))");
  EXPECT_EQ(parsed("-x^2"), "(-(x ^ 2))");
  EXPECT_EQ(parsed("-a * b"), "((-a) * b)");
  EXPECT_EQ(parsed("a * -b"), "(a * (-b))");
  EXPECT_EQ(parsed("a - -b"), "(a - (-b))");
  EXPECT_EQ(parsed("2^-x^2"), "(2 ^ (-(x ^ 2)))");
  EXPECT_EQ(parsed("--x"), "(-(-x))");
  EXPECT_EQ(parsed("(a + b) * c"), "((a + b) * c)");
  EXPECT_EQ(parsed("a + b @ c ^ d.T"), "(a + (b @ (c ^ d.T)))");
}

TEST(Parser, UnaryPlusIsDroppedAndMinusOnNumbersStays) {
  EXPECT_EQ(parsed("+x"), "x");
  EXPECT_EQ(parsed("a * +b"), "(a * b)");
  const ExprPtr minus = parseExpression("-2");
  ASSERT_EQ(minus->kind, ExprKind::Unary);
  EXPECT_EQ(minus->args.at(0)->kind, ExprKind::Number);
  EXPECT_EQ(minus->args.at(0)->number, 2.0);
}

TEST(Parser, TheBriefsExamples) {
  EXPECT_EQ(parsed("v + dt * aba(q, v, u)"), "(v + (dt * aba(q, v, u)))");
  EXPECT_EQ(parsed("integrate(q, dt * v_next)"), "integrate(q, (dt * v_next))");
  EXPECT_EQ(parsed("frame_position(q, 'panda_hand') - target"), "(frame_position(q, 'panda_hand') - target)");
  EXPECT_EQ(parsed("sumsq(e) + 1e-3 * sumsq(tau)"), "(sumsq(e) + (0.001 * sumsq(tau)))");
}

TEST(Parser, Numbers) {
  const std::vector<std::pair<std::string, double>> cases = {
      {"2", 2.0}, {".5", 0.5}, {"0.25", 0.25}, {"1e-3", 1e-3}, {"2.5E+3", 2500.0}, {"3.", 3.0}, {"1.e2", 100.0},
      {"007", 7.0}, {"1E5", 1e5}};
  for (const auto& [text, value] : cases) {
    const ExprPtr e = parseExpression(text);
    ASSERT_EQ(e->kind, ExprKind::Number) << text;
    EXPECT_DOUBLE_EQ(e->number, value) << text;
  }
}

TEST(Parser, NamesAndStrings) {
  const ExprPtr name = parseExpression("  _v_next2 ");
  ASSERT_EQ(name->kind, ExprKind::Name);
  EXPECT_EQ(name->text, "_v_next2");
  EXPECT_EQ(name->column, 3);
  const ExprPtr single = parseExpression("'panda hand'");
  ASSERT_EQ(single->kind, ExprKind::String);
  EXPECT_EQ(single->text, "panda hand");
  const ExprPtr dbl = parseExpression("\"it's\"");
  ASSERT_EQ(dbl->kind, ExprKind::String);
  EXPECT_EQ(dbl->text, "it's");
}

TEST(Parser, Calls) {
  EXPECT_EQ(parsed("f()"), "f()");
  EXPECT_EQ(parsed("f (x)"), "f(x)");
  EXPECT_EQ(parsed("f(g(x), [1, 2], 'a')"), "f(g(x), [1, 2], 'a')");
  EXPECT_EQ(parsed("f(x)[2]"), "f(x)[2]");
}

TEST(Parser, Indexing) {
  EXPECT_EQ(parsed("x[i]"), "x[i]");
  EXPECT_EQ(parsed("x[i:j]"), "x[i:j]");
  EXPECT_EQ(parsed("x[:j]"), "x[:j]");
  EXPECT_EQ(parsed("x[i:]"), "x[i:]");
  EXPECT_EQ(parsed("x[:]"), "x[:]");
  EXPECT_EQ(parsed("M[i:j, k:l]"), "M[i:j, k:l]");
  EXPECT_EQ(parsed("M[i, :]"), "M[i, :]");
  EXPECT_EQ(parsed("x[nq - 1 : 2 * nq]"), "x[(nq - 1):(2 * nq)]");
  EXPECT_EQ(parsed("x[0][1]"), "x[0][1]");
  const ExprPtr plain = parseExpression("x[3]");
  ASSERT_EQ(plain->ranges.size(), 1u);
  EXPECT_FALSE(plain->ranges[0].is_slice);
  EXPECT_EQ(plain->ranges[0].end, nullptr);
  const ExprPtr all = parseExpression("x[:]");
  EXPECT_TRUE(all->ranges[0].is_slice);
  EXPECT_EQ(all->ranges[0].begin, nullptr);
  EXPECT_EQ(all->ranges[0].end, nullptr);
}

TEST(Parser, TransposeAndPostfixChains) {
  EXPECT_EQ(parsed("J.T"), "J.T");
  EXPECT_EQ(parsed("(a@b).T"), "(a @ b).T");
  EXPECT_EQ(parsed("x[0:3].T"), "x[0:3].T");
  EXPECT_EQ(parsed("J.T @ J"), "(J.T @ J)");
  EXPECT_EQ(parsed("f(x).T.T[1, 2:]"), "f(x).T.T[1, 2:]");
  EXPECT_EQ(parsed("[1, 2].T"), "[1, 2].T");
}

TEST(Parser, MatrixLiterals) {
  EXPECT_EQ(parsed("[a, b; c, d]"), "[a, b; c, d]");
  const ExprPtr column = parseExpression("[a; b]");
  ASSERT_EQ(column->kind, ExprKind::Matrix);
  ASSERT_EQ(column->rows.size(), 2u);
  EXPECT_EQ(column->rows[0].size(), 1u);
  EXPECT_EQ(column->rows[1].size(), 1u);
  const ExprPtr row = parseExpression("[a, b]");
  ASSERT_EQ(row->rows.size(), 1u);
  EXPECT_EQ(row->rows[0].size(), 2u);
  EXPECT_EQ(parsed("[[a]; -b + 1, f(c)]"), "[[a]; ((-b) + 1), f(c)]");
}

TEST(Parser, WhitespaceIsIgnored) {
  EXPECT_EQ(parsed("\ta\n+\r\n b *c "), "(a + (b * c))");
}

TEST(Parser, ColumnsAreTheNodesFirstCharacters) {
  const ExprPtr e = parseExpression("v + dt * aba(q, v, u)");
  EXPECT_EQ(e->column, 1);
  const ExprPtr product = e->args.at(1);
  EXPECT_EQ(product->column, 5);
  const ExprPtr call = product->args.at(1);
  EXPECT_EQ(call->column, 10);
  EXPECT_EQ(call->args.at(0)->column, 14);
  EXPECT_EQ(call->args.at(2)->column, 20);

  const ExprPtr grouped = parseExpression("(a + b) * c");
  EXPECT_EQ(grouped->column, 1);
  EXPECT_EQ(grouped->args.at(0)->column, 2);
  EXPECT_EQ(parseExpression("  -x")->column, 3);
  EXPECT_EQ(parseExpression(" (a@b).T")->column, 2);
  const ExprPtr index = parseExpression("x + M[1, 'a']");
  EXPECT_EQ(index->args.at(1)->column, 5);
  EXPECT_EQ(index->args.at(1)->ranges.at(1).begin->column, 10);
  EXPECT_EQ(parseExpression("1 + [2]")->args.at(1)->column, 5);
}

struct BadInput {
  std::string text;
  int column;
  std::string phrase;
};

TEST(Parser, ErrorsNameTheColumnWhatWasExpectedAndWhatWasFound) {
  const std::vector<BadInput> cases = {
      {"", 1, "expected an expression, found end of expression"},
      {"   ", 4, "expected an expression"},
      {"a +", 3, "expected an operand after '+', found end of expression"},
      {"a + * b", 3, "expected an operand after '+', found '*'"},
      {"a ^", 3, "after '^'"},
      {"-", 1, "expected an operand after '-'"},
      {"* a", 1, "expected an expression, found '*'"},
      {"(* a)", 2, "expected an expression inside the parenthesis opened at column 1, found '*'"},
      {"v + dt * aba(q, v", 18,
       "expected ')' to close the call of 'aba' opened at column 10, found end of expression"},
      {"f(a b)", 5, "expected ',' or ')' to close the call of 'f' opened at column 1, found name 'b'"},
      {"f(a,)", 5, "expected an argument of 'f', found ')'"},
      {"(a", 3, "expected ')' to close the parenthesis opened at column 1, found end of expression"},
      {"()", 2, "expected an expression inside the parenthesis opened at column 1, found ')'"},
      {"a b", 3, "expected an operator or the end of the expression, found name 'b'"},
      {"a)", 2, "found ')'"},
      {"[1]]", 4, "closes nothing"},
      {"a, b", 2, "found ','"},
      {"2(3)", 2, "only a name can be called"},
      {"(f)(x)", 4, "only a name can be called"},
      {"1e", 3, "expected the digits of the exponent after '1e', found end of expression"},
      {"2.5e+ 1", 6, "exponent"},
      {"1..2", 3, "malformed number starting at column 1"},
      {"x + 12abc", 7, "found character 'a'"},
      {"1e999", 1, "within the range of a double"},
      {"f('abc)", 3, "unterminated string: expected a closing ' for the string opened at column 3"},
      {"\"abc", 1, "expected a closing \""},
      {"a $ b", 3, "found character '$'"},
      {"a # b", 3, "expected a number, name, string, operator or bracket"},
      {"\xc3\xa9", 1, "non-ASCII byte 0xC3"},
      {"x.y", 3, "expected 'T' after '.' (the transpose x.T), found 'y'"},
      {"x.Tx", 3, "found 'Tx'"},
      {"x.", 3, "found end of expression"},
      {"[]", 2, "expected a matrix element"},
      {"[a,]", 4, "expected a matrix element"},
      {"[a;;b]", 4, "expected a matrix element"},
      {"[a;]", 4, "found ']'"},
      {"[a b]", 4, "expected ',', ';' or ']' to close the matrix opened at column 1, found name 'b'"},
      {"x[]", 3, "expected an index or a slice, found ']'"},
      {"x[1", 4, "expected ':', ',' or ']' to close the index opened at column 2"},
      {"x[1:", 5, "expected the end of the slice"},
      {"x[1:2:3]", 6, "expected ',' or ']' to close the index opened at column 2, found ':'"},
      {"x[1, 2, 3]", 7, "at most two ranges"},
      {"x[, 1]", 3, "expected an index or a slice, found ','"},
  };
  for (const BadInput& bad : cases) {
    try {
      parseExpression(bad.text);
      ADD_FAILURE() << "no error for '" << bad.text << "'";
    } catch (const ExpressionTooLarge& e) {
      ADD_FAILURE() << "'" << bad.text << "' is not too large: " << e.what();
    } catch (const ExpressionError& e) {
      EXPECT_EQ(e.column(), bad.column) << bad.text << ": " << e.what();
      EXPECT_NE(e.message().find(bad.phrase), std::string::npos) << bad.text << ": " << e.what();
      EXPECT_EQ(std::string(e.what()), "column " + std::to_string(e.column()) + ": " + e.message());
    }
  }
}

// The error parseExpression throws for `text`, which must be ExpressionTooLarge.
ExpressionTooLarge tooLarge(const std::string& text, const ParseLimits& limits = {}) {
  try {
    parseExpression(text, limits);
  } catch (const ExpressionTooLarge& e) {
    return e;
  }
  ADD_FAILURE() << "no ExpressionTooLarge for text of " << text.size() << " characters";
  return ExpressionTooLarge(0, "");
}

ParseLimits longTextAllowed() {
  ParseLimits limits;
  limits.max_length = std::size_t{1} << 24;
  return limits;
}

TEST(ParserLimits, HundredThousandParenthesesFailWithoutCrashing) {
  const std::string parens(100000, '(');
  EXPECT_NE(tooLarge(parens).message().find("limit of 65536 characters"), std::string::npos);
  const ExpressionTooLarge deep = tooLarge(parens + "x" + std::string(100000, ')'), longTextAllowed());
  EXPECT_NE(deep.message().find("limit of 64 levels"), std::string::npos) << deep.what();
  EXPECT_EQ(deep.column(), 65);
}

TEST(ParserLimits, EveryKindOfNestingIsBounded) {
  const ParseLimits limits = longTextAllowed();
  auto repeated = [](const std::string& piece, int times) {
    std::string out;
    for (int i = 0; i < times; ++i) out += piece;
    return out;
  };
  for (const std::string& text : {repeated("-", 100000) + "x", repeated("+ ", 100000) + "x",
                                  repeated("[", 100000), repeated("f(", 100000), repeated("x^", 100000) + "x",
                                  repeated("x[", 100000), repeated("(-[f(", 30000)}) {
    EXPECT_NE(tooLarge(text, limits).message().find("nests deeper"), std::string::npos) << text.substr(0, 20);
  }
}

TEST(ParserLimits, DepthLimitIsExact) {
  ParseLimits limits;
  limits.max_depth = 3;
  EXPECT_EQ(show(parseExpression("(((x)))", limits)), "x");
  EXPECT_EQ(show(parseExpression("f([-x])", limits)), "f([(-x)])");
  EXPECT_EQ(tooLarge("((((x))))", limits).column(), 4);
  EXPECT_EQ(tooLarge("f([(-x)])", limits).column(), 5);
  EXPECT_EQ(tooLarge("a^b^c^d^e", limits).column(), 8);
}

TEST(ParserLimits, LongText) {
  const std::string padded = "x" + std::string(70000, ' ');
  const ExpressionTooLarge error = tooLarge(padded);
  EXPECT_NE(error.message().find("70001 characters long"), std::string::npos) << error.what();
  EXPECT_EQ(error.column(), 65537);
  EXPECT_EQ(show(parseExpression(padded, longTextAllowed())), "x");
}

// "x + x + ... + x" with `terms` terms: 2 * terms - 1 nodes.
std::string chain(int terms) {
  std::string text = "x";
  for (int i = 1; i < terms; ++i) text += "+x";
  return text;
}

TEST(ParserLimits, ManyNodes) {
  EXPECT_NO_THROW(parseExpression(chain(10000)));  // 19999 nodes
  const ExpressionTooLarge error = tooLarge(chain(10001));
  EXPECT_NE(error.message().find("limit of 20000"), std::string::npos) << error.what();
  ParseLimits small;
  small.max_nodes = 5;
  EXPECT_NO_THROW(parseExpression("f(a, b, c, d)", small));
  EXPECT_THROW(parseExpression("f(a, b, c, d, e)", small), ExpressionTooLarge);
  EXPECT_THROW(parseExpression("[1, 2; 3, 4; 5]", small), ExpressionTooLarge);
}

// A million-node expression parses in well under a second; it is a flat call, because
// a left-deep chain that long would overflow the stack when the tree is destroyed.
TEST(ParserLimits, LinearTime) {
  ParseLimits limits = longTextAllowed();
  limits.max_nodes = 10'000'000;
  std::string text = "f(x";
  for (int i = 0; i < 300'000; ++i) text += ", x+-x";
  text += ")";
  const auto start = std::chrono::steady_clock::now();
  const ExprPtr e = parseExpression(text, limits);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(e->args.size(), 300'001u);
  EXPECT_LT(seconds, 5.0);
}

}  // namespace
}  // namespace robodiff::language
