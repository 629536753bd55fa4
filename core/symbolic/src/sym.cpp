#include "robodiff/symbolic/sym.hpp"

#include <ostream>
#include <string>

namespace robodiff::symbolic {
namespace {

// The graph an operation on these arguments records into; nullptr when all are detached.
Graph* commonGraph(std::initializer_list<const Sym*> args) {
  Graph* graph = nullptr;
  for (const Sym* s : args) {
    if (s->isDetached()) continue;
    if (graph && graph != s->graph())
      throw std::invalid_argument("robodiff::symbolic::Sym: an operation mixes values of two different graphs");
    graph = s->graph();
  }
  return graph;
}

[[noreturn]] void throwComparison(const char* op) {
  throw NonConstantComparison(std::string("robodiff::symbolic::Sym: comparison (") + op +
                              ") of a non-constant symbolic value: traced code must not branch on values "
                              "(use min, max, abs or selectPositive)");
}

// Both sides constant, or throw naming the comparison.
void requireConstants(const Sym& a, const Sym& b, const char* op) {
  if (!a.isConstant() || !b.isConstant()) throwComparison(op);
}

}  // namespace

NodeId Sym::node() const {
  if (!graph_) throw std::logic_error("robodiff::symbolic::Sym::node: a detached constant has no node (use nodeIn)");
  return id_;
}

NodeId Sym::nodeIn(Graph& graph) const {
  if (!graph_) return graph.constant(value_);
  if (graph_ != &graph) throw std::invalid_argument("robodiff::symbolic::Sym::nodeIn: the value belongs to another graph");
  return id_;
}

bool Sym::isConstant() const { return !graph_ || graph_->node(id_).op == Op::Constant; }

double Sym::constantValue() const {
  if (!graph_) return value_;
  const Node& n = graph_->node(id_);
  if (n.op != Op::Constant)
    throw std::logic_error("robodiff::symbolic::Sym::constantValue: node " + std::to_string(id_) + " (" +
                           toString(n.op) + ") is not a constant");
  return n.value;
}

Sym apply(Op op, const Sym& a) {
  Graph* g = a.graph();
  if (!g) return Sym(evaluateOp(op, a.constantValue()));
  return Sym(*g, g->unary(op, a.node()));
}

Sym apply(Op op, const Sym& a, const Sym& b) {
  Graph* g = commonGraph({&a, &b});
  if (!g) return Sym(evaluateOp(op, a.constantValue(), b.constantValue()));
  const NodeId na = a.nodeIn(*g);
  const NodeId nb = b.nodeIn(*g);
  return Sym(*g, g->binary(op, na, nb));
}

Sym selectPositive(const Sym& condition, const Sym& if_positive, const Sym& otherwise) {
  Graph* g = commonGraph({&condition, &if_positive, &otherwise});
  if (!g)
    return Sym(evaluateOp(Op::SelectPositive, condition.constantValue(), if_positive.constantValue(),
                          otherwise.constantValue()));
  const NodeId c = condition.nodeIn(*g);
  const NodeId p = if_positive.nodeIn(*g);
  const NodeId o = otherwise.nodeIn(*g);
  return Sym(*g, g->selectPositive(c, p, o));
}

Sym operator+(const Sym& a, const Sym& b) { return apply(Op::Add, a, b); }
Sym operator-(const Sym& a, const Sym& b) { return apply(Op::Sub, a, b); }
Sym operator*(const Sym& a, const Sym& b) { return apply(Op::Mul, a, b); }
Sym operator/(const Sym& a, const Sym& b) { return apply(Op::Div, a, b); }
Sym operator-(const Sym& a) { return apply(Op::Neg, a); }

bool operator<(const Sym& a, const Sym& b) { return requireConstants(a, b, "<"), a.constantValue() < b.constantValue(); }
bool operator<=(const Sym& a, const Sym& b) { return requireConstants(a, b, "<="), a.constantValue() <= b.constantValue(); }
bool operator>(const Sym& a, const Sym& b) { return requireConstants(a, b, ">"), a.constantValue() > b.constantValue(); }
bool operator>=(const Sym& a, const Sym& b) { return requireConstants(a, b, ">="), a.constantValue() >= b.constantValue(); }
bool operator==(const Sym& a, const Sym& b) { return requireConstants(a, b, "=="), a.constantValue() == b.constantValue(); }
bool operator!=(const Sym& a, const Sym& b) { return requireConstants(a, b, "!="), a.constantValue() != b.constantValue(); }

Sym sin(const Sym& x) { return apply(Op::Sin, x); }
Sym cos(const Sym& x) { return apply(Op::Cos, x); }
Sym tan(const Sym& x) { return apply(Op::Tan, x); }
Sym asin(const Sym& x) { return apply(Op::Asin, x); }
Sym acos(const Sym& x) { return apply(Op::Acos, x); }
Sym atan(const Sym& x) { return apply(Op::Atan, x); }
Sym exp(const Sym& x) { return apply(Op::Exp, x); }
Sym log(const Sym& x) { return apply(Op::Log, x); }
Sym sqrt(const Sym& x) { return apply(Op::Sqrt, x); }
Sym tanh(const Sym& x) { return apply(Op::Tanh, x); }
Sym abs(const Sym& x) { return apply(Op::Abs, x); }
Sym atan2(const Sym& y, const Sym& x) { return apply(Op::Atan2, y, x); }
Sym pow(const Sym& base, const Sym& exponent) { return apply(Op::Pow, base, exponent); }
Sym min(const Sym& a, const Sym& b) { return apply(Op::Min, a, b); }
Sym max(const Sym& a, const Sym& b) { return apply(Op::Max, a, b); }

std::ostream& operator<<(std::ostream& os, const Sym& x) {
  if (x.isConstant()) return os << x.constantValue();
  return os << '%' << x.node();
}

}  // namespace robodiff::symbolic
