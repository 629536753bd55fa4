// What a user function's expression evaluates to: a matrix on a scalar S (double for
// the reference, symbolic::Sym for tracing) and, when tracing derivatives, its tangent:
// d value / d (the tangent columns of every input some output differentiates against),
// one row per entry of the value in row-major order, or nv rows for a configuration
// (whose derivatives live in the tangent space).
#pragma once

#include <stdexcept>
#include <string>
#include <type_traits>

#include "robodiff/spatial/math.hpp"
#include "robodiff/symbolic/sym.hpp"

namespace robodiff::detail {

template <class S> inline constexpr bool kTracesTangents = std::is_same_v<S, symbolic::Sym>;

template <class S> struct Value {
  MatX<S> m;
  bool configuration = false;  // nq coordinates of the robot's configuration
  bool has_tangent = false;    // false: the tangent is zero (constants, fixed inputs)
  MatX<S> d;                   // tangent rows x columns, when has_tangent

  Eigen::Index rows() const { return m.rows(); }
  Eigen::Index cols() const { return m.cols(); }
  Eigen::Index size() const { return m.size(); }
  bool isScalar() const { return m.size() == 1 && !configuration; }
  bool isVector() const { return m.cols() == 1; }
  // The tangent row of entry (r, c).
  Eigen::Index at(Eigen::Index r, Eigen::Index c) const { return r * m.cols() + c; }
  const S& flat(Eigen::Index k) const { return m(k / m.cols(), k % m.cols()); }
  S& flat(Eigen::Index k) { return m(k / m.cols(), k % m.cols()); }
};

inline std::string shapeText(Eigen::Index rows, Eigen::Index cols) {
  return std::to_string(rows) + "x" + std::to_string(cols);
}
template <class S> std::string shapeOf(const Value<S>& v) {
  return v.configuration ? "configuration (" + std::to_string(v.rows()) + ")" : shapeText(v.rows(), v.cols());
}

// An error in an expression, at a column of the text being evaluated; the evaluator adds
// which define or output that text belongs to.
class EvalError : public std::runtime_error {
 public:
  EvalError(int column, const std::string& what) : std::runtime_error(what), column_(column) {}
  int column() const { return column_; }

 private:
  int column_;
};

// Past the limit on what the expressions compute (Evaluator's budget): a resource error,
// SpecTooLarge (RESOURCE_EXHAUSTED) once located.
class EvalTooLarge : public EvalError {
 public:
  using EvalError::EvalError;
};

inline bool isZero(const symbolic::Sym& x) { return x.isConstant() && x.constantValue() == 0.0; }
inline bool isZero(double) { return false; }

}  // namespace robodiff::detail
