#include "derivative_rules.hpp"

#include <stdexcept>
#include <string>

namespace robodiff::symbolic::detail {
namespace {

// d node / d argument k of a smooth operation: sign * factor, or sign / factor.
struct Partial {
  NodeId factor = 1;  // the constant 1 node: the identity
  bool divide = false;
  bool negative = false;
};

Partial partial(Graph& g, NodeId id, const Node& n, int k) {
  const NodeId a = n.args[0], b = n.args[1];
  auto mul = [&g](NodeId x, NodeId y) { return g.binary(Op::Mul, x, y); };
  auto sub = [&g](NodeId x, NodeId y) { return g.binary(Op::Sub, x, y); };
  auto add = [&g](NodeId x, NodeId y) { return g.binary(Op::Add, x, y); };
  auto div = [&g](NodeId x, NodeId y) { return g.binary(Op::Div, x, y); };
  const NodeId one = g.one();
  switch (n.op) {
    case Op::Neg: return {one, false, true};
    case Op::Add: return {one, false, false};
    case Op::Sub: return {one, false, k == 1};
    case Op::Mul: return {k == 0 ? b : a, false, false};
    case Op::Div:  // d/da = 1 / b, d/db = -(a / b) / b
      return k == 0 ? Partial{b, true, false} : Partial{div(id, b), false, true};
    case Op::Sin: return {g.unary(Op::Cos, a), false, false};
    case Op::Cos: return {g.unary(Op::Sin, a), false, true};
    case Op::Tan: return {add(one, mul(id, id)), false, false};
    case Op::Asin: return {g.unary(Op::Sqrt, sub(one, mul(a, a))), true, false};
    case Op::Acos: return {g.unary(Op::Sqrt, sub(one, mul(a, a))), true, true};
    case Op::Atan: return {add(one, mul(a, a)), true, false};
    case Op::Exp: return {id, false, false};
    case Op::Log: return {a, true, false};
    case Op::Sqrt: return {mul(g.constant(2.0), id), true, false};
    case Op::Tanh: return {sub(one, mul(id, id)), false, false};
    case Op::Atan2: {  // atan2(y = a, x = b): d/dy = x / (x^2 + y^2), d/dx = -y / (x^2 + y^2)
      const NodeId den = add(mul(a, a), mul(b, b));
      return k == 0 ? Partial{div(b, den), false, false} : Partial{div(a, den), false, true};
    }
    case Op::Pow:  // d/da = b a^(b-1), d/db = a^b log(a)
      if (k == 0) return {mul(b, g.binary(Op::Pow, a, sub(b, one))), false, false};
      return {mul(id, g.unary(Op::Log, a)), false, false};
    default: break;
  }
  throw std::logic_error(std::string("derivative rules: no partial derivative for ") + toString(n.op));
}

// t * partial, as a signed term.
Term scaled(Graph& g, const Partial& p, NodeId t) {
  if (p.factor == g.one()) return {t, p.negative};
  return {g.binary(p.divide ? Op::Div : Op::Mul, t, p.factor), p.negative};
}

// The condition under which min / max take their first argument.
NodeId firstWins(Graph& g, const Node& n) {
  return n.op == Op::Min ? g.binary(Op::Sub, n.args[1], n.args[0]) : g.binary(Op::Sub, n.args[0], n.args[1]);
}

}  // namespace

NodeId accumulate(Graph& g, NodeId sum, const Term& term) {
  if (term.node == g.zero()) return sum;
  if (sum == g.zero()) return term.negative ? g.unary(Op::Neg, term.node) : term.node;
  return g.binary(term.negative ? Op::Sub : Op::Add, sum, term.node);
}

NodeId pushTangent(Graph& g, NodeId id, const Node& n, const NodeId dot[3]) {
  const NodeId zero = g.zero();
  switch (n.op) {
    case Op::Abs:  // |a|' = a > 0 ? a' : -a'
      return g.selectPositive(n.args[0], dot[0], g.unary(Op::Neg, dot[0]));
    case Op::Min:
    case Op::Max:
      return g.selectPositive(firstWins(g, n), dot[0], dot[1]);
    case Op::SelectPositive:  // the condition only chooses: its tangent does not enter
      return g.selectPositive(n.args[0], dot[1], dot[2]);
    default: {
      NodeId sum = zero;
      for (int k = 0; k < arity(n.op); ++k)
        if (dot[k] != zero) sum = accumulate(g, sum, scaled(g, partial(g, id, n, k), dot[k]));
      return sum;
    }
  }
}

void pullAdjoint(Graph& g, NodeId id, const Node& n, NodeId bar, const bool wanted[3], Term out[3]) {
  const NodeId zero = g.zero();
  out[0] = out[1] = out[2] = Term{};
  switch (n.op) {
    case Op::Abs:
      if (wanted[0]) out[0] = {g.selectPositive(n.args[0], bar, g.unary(Op::Neg, bar)), false};
      return;
    case Op::Min:
    case Op::Max: {
      const NodeId c = firstWins(g, n);
      if (wanted[0]) out[0] = {g.selectPositive(c, bar, zero), false};
      if (wanted[1]) out[1] = {g.selectPositive(c, zero, bar), false};
      return;
    }
    case Op::SelectPositive:
      if (wanted[1]) out[1] = {g.selectPositive(n.args[0], bar, zero), false};
      if (wanted[2]) out[2] = {g.selectPositive(n.args[0], zero, bar), false};
      return;
    default:
      for (int k = 0; k < arity(n.op); ++k)
        if (wanted[k]) out[k] = scaled(g, partial(g, id, n, k), bar);
      return;
  }
}

}  // namespace robodiff::symbolic::detail
