// The expression language of user functions: the syntax tree one expression parses
// into. Values are matrices of reals (a vector is n x 1, a scalar 1 x 1); what the
// names and calls mean (inputs, defines, functions, model primitives) is decided by the
// evaluator (core/functions), not here. docs/function-language.md is the reference.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace robodiff::language {

struct Expr;
using ExprPtr = std::shared_ptr<const Expr>;

enum class ExprKind {
  Number,     // 2, 0.5, 1e-3: `number`
  String,     // 'panda_hand' or "panda_hand": `text` (a frame, shape or reference name)
  Name,       // q, dt, v_next, nq: `text`
  Call,       // f(a, b): `text` the function name, `args` the arguments
  Unary,      // -x: `text` "-", `args` {x} (the parser drops unary plus: +x is x)
  Binary,     // a + b: `text` one of + - * / ^ @, `args` {a, b}
  Matrix,     // [a, b; c, d]: `rows`, each a list of elements side by side; rows stacked
  Index,      // x[i], x[i:j], M[i:j, k:l]: `args` {x}, `ranges` one or two
  Transpose,  // x.T: `args` {x}
};

// One index or slice of an Index node. A plain index x[i] has `begin` set and
// is_slice false; a slice x[i:j] has is_slice true and either bound may be missing
// (x[:j], x[i:], x[:]). Bounds are expressions; the evaluator requires them to be
// integer constants (numbers, nq, nv and arithmetic on them), 0-based, end excluded.
struct IndexRange {
  ExprPtr begin, end;
  bool is_slice = false;
};

struct Expr {
  ExprKind kind = ExprKind::Number;
  double number = 0.0;
  std::string text;
  std::vector<ExprPtr> args;
  std::vector<std::vector<ExprPtr>> rows;  // Matrix
  std::vector<IndexRange> ranges;          // Index
  // 1-based column of the node's first character (parser.hpp): for a Binary, Index or
  // Transpose node where its first operand begins, counting an opening parenthesis.
  int column = 1;
};

}  // namespace robodiff::language
