// Evaluates a user function's expressions on Value<S>: names (inputs, defines, nq, nv,
// pi), operators, matrix literals, indexing, math functions and model primitives.
// Defines are evaluated once, when first used, and shared. An error is reported as a
// SpecError naming the define or output whose text holds it, the column, and the text
// with a caret under the column.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>

#include "robodiff/functions/function_spec.hpp"
#include "user_primitives.hpp"

namespace robodiff::detail {

// An integer constant expression: numbers, nq, nv, unary minus, + - * (sizes, indices).
int constantInteger(const language::Expr& e, const Model& model, const std::string& what);

// Every input's size: nq for a configuration, its size expression's value, or the
// fixed numbers' count. Throws SpecError naming the input.
std::map<std::string, int> inputSizes(const Model& model, const UserFunction& f);

// The most entries one evaluation may compute: every value and tangent an expression
// node produces, in all, and a matrix product's multiply-adds before it runs. Real specs
// stay below 1% of it; `eye(10000) @ eye(10000)` would otherwise take hours and GBs.
inline constexpr std::uint64_t kMaxEvaluatedEntries = 20'000'000;

template <class S> class Evaluator {
 public:
  Evaluator(const PrimitiveContext& context, std::map<std::string, Value<S>> inputs);

  // The value of outputs[k].of.
  Value<S> output(std::size_t k);
  // A configuration as plain coordinates (the tangent mapped to them); other values as is.
  Value<S> coordinates(const Value<S>& v);

 private:
  Value<S> eval(const language::Expr& e);
  Value<S> evalNode(const language::Expr& e);
  // Adds `entries` to the work done; EvalTooLarge past kMaxEvaluatedEntries.
  void charge(std::uint64_t entries, int column);
  Value<S> name(const language::Expr& e);
  Value<S> call(const language::Expr& e);
  Value<S> binary(const language::Expr& e);
  Value<S> matrix(const language::Expr& e);
  Value<S> index(const language::Expr& e);
  Value<S> evalCoordinates(const language::ExprPtr& e) { return coordinates(eval(*e)); }
  Value<S> located(const language::Expr& e, const std::string& path, const std::string& text);

  const PrimitiveContext& context_;
  std::map<std::string, Value<S>> inputs_;
  std::map<std::string, Value<S>> defines_;  // evaluated so far
  std::set<std::string> evaluating_;         // defines being evaluated (cycles)
  std::uint64_t work_ = 0;                   // entries computed so far (charge)
};

}  // namespace robodiff::detail
