// Sym: the symbolic scalar. Running a core/dynamics algorithm on Sym records every
// arithmetic operation as a node of a Graph (tracing) instead of computing a number.
//
// A Sym is either
//  - bound: a graph pointer and a node id in that graph, or
//  - detached: a plain constant with no graph (default-constructed Syms, Sym(double),
//    Eigen's Zero()/Identity(), the model's constants). Operations on detached
//    constants only are computed at once (with the graph's own evaluateOp, so the
//    results are the bits a graph would fold to); mixing a detached constant with a
//    bound Sym turns the constant into a constant node of that graph.
// So no global "current graph" exists: the graph travels with the values, and several
// graphs may be traced side by side (mixing two graphs in one operation throws).
// A bound Sym does not own its graph: the graph must outlive it.
//
// Tracing must not branch on values. Comparison operators exist (Eigen and generic code
// may compare constants), but throw NonConstantComparison unless both sides are
// constants; branch-free choices are min, max, abs and selectPositive.
#pragma once

#include <iosfwd>
#include <stdexcept>

#include <Eigen/Core>

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::symbolic {

// A comparison of symbolic values that are not constants: the traced code branches
// on a value, which a straight-line graph cannot represent.
class NonConstantComparison : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

class Sym {
 public:
  Sym() = default;  // the detached constant 0
  Sym(double value) : value_(value) {}  // NOLINT(google-explicit-constructor): S(0), 2.0 * x
  Sym(Graph& graph, NodeId id) : graph_(&graph), id_(id) {}

  bool isDetached() const { return graph_ == nullptr; }
  Graph* graph() const { return graph_; }
  // The node of a bound Sym (throws std::logic_error for a detached constant).
  NodeId node() const;
  // The node in `graph`: a detached constant becomes (or finds) a constant node there.
  NodeId nodeIn(Graph& graph) const;

  // Detached, or bound to a constant node.
  bool isConstant() const;
  // The value of a constant (throws std::logic_error for a non-constant).
  double constantValue() const;

  Sym& operator+=(const Sym& o) { return *this = *this + o; }
  Sym& operator-=(const Sym& o) { return *this = *this - o; }
  Sym& operator*=(const Sym& o) { return *this = *this * o; }
  Sym& operator/=(const Sym& o) { return *this = *this / o; }

  // Non-template friends: a double on either side converts through Sym(double).
  friend Sym operator+(const Sym& a, const Sym& b);
  friend Sym operator-(const Sym& a, const Sym& b);
  friend Sym operator*(const Sym& a, const Sym& b);
  friend Sym operator/(const Sym& a, const Sym& b);
  friend Sym operator-(const Sym& a);
  friend Sym operator+(const Sym& a) { return a; }

  friend bool operator<(const Sym& a, const Sym& b);
  friend bool operator<=(const Sym& a, const Sym& b);
  friend bool operator>(const Sym& a, const Sym& b);
  friend bool operator>=(const Sym& a, const Sym& b);
  friend bool operator==(const Sym& a, const Sym& b);
  friend bool operator!=(const Sym& a, const Sym& b);

 private:
  Graph* graph_ = nullptr;
  NodeId id_ = 0;       // bound only
  double value_ = 0.0;  // detached only
};

// op applied to Syms: computed at once when every argument is detached, else a node.
Sym apply(Op op, const Sym& a);
Sym apply(Op op, const Sym& a, const Sym& b);

// Math functions, found by argument-dependent lookup from robodiff::math and Eigen.
Sym sin(const Sym& x);
Sym cos(const Sym& x);
Sym tan(const Sym& x);
Sym asin(const Sym& x);
Sym acos(const Sym& x);
Sym atan(const Sym& x);
Sym exp(const Sym& x);
Sym log(const Sym& x);
Sym sqrt(const Sym& x);
Sym tanh(const Sym& x);
Sym abs(const Sym& x);
Sym atan2(const Sym& y, const Sym& x);
Sym pow(const Sym& base, const Sym& exponent);
Sym min(const Sym& a, const Sym& b);
Sym max(const Sym& a, const Sym& b);
// condition > 0 ? if_positive : otherwise, as one branch-free node.
Sym selectPositive(const Sym& condition, const Sym& if_positive, const Sym& otherwise);

// Prints a constant's value, or "%<id>" for a node.
std::ostream& operator<<(std::ostream& os, const Sym& x);

}  // namespace robodiff::symbolic

namespace Eigen {

template <> struct NumTraits<robodiff::symbolic::Sym> : NumTraits<double> {
  using Real = robodiff::symbolic::Sym;
  using NonInteger = robodiff::symbolic::Sym;
  using Nested = robodiff::symbolic::Sym;
  using Literal = robodiff::symbolic::Sym;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,  // Sym has a constructor: Eigen must run it
    ReadCost = 1,
    AddCost = 1,
    MulCost = 1
  };
  static Real epsilon() { return NumTraits<double>::epsilon(); }
  static Real dummy_precision() { return NumTraits<double>::dummy_precision(); }
  static Real highest() { return NumTraits<double>::highest(); }
  static Real lowest() { return NumTraits<double>::lowest(); }
};

// Sym and double mix in Eigen expressions (matrix of Sym times a double, and back).
template <> struct ScalarBinaryOpTraits<robodiff::symbolic::Sym, double> {
  using ReturnType = robodiff::symbolic::Sym;
};
template <> struct ScalarBinaryOpTraits<double, robodiff::symbolic::Sym> {
  using ReturnType = robodiff::symbolic::Sym;
};

}  // namespace Eigen
