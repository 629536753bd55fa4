// The operators and math functions of the expression language on Value<S>: the value,
// its shape rules, and (when tracing, kTracesTangents<S>) the tangent by the chain rule.
// Operands are plain matrices here: the evaluator turns configurations into their
// coordinates first. Shape errors throw EvalError(column, both shapes).
#pragma once

#include <cmath>
#include <functional>

#include "user_value.hpp"

namespace robodiff::detail {

// tangent row `r` of `out` += c * tangent row `sr` of `src` (zeros skipped: most are).
template <class S> void addTangentRow(Value<S>& out, Eigen::Index r, const S& c, const Value<S>& src, Eigen::Index sr) {
  if constexpr (kTracesTangents<S>) {
    if (!src.has_tangent || isZero(c)) return;
    for (Eigen::Index j = 0; j < src.d.cols(); ++j) {
      const S& x = src.d(sr, j);
      if (isZero(x)) continue;
      out.d(r, j) = isZero(out.d(r, j)) ? S(c * x) : S(out.d(r, j) + c * x);
    }
  }
}

// A value of the given shape whose tangent (zero) is ready to be added to, when any
// operand carries one.
template <class S> Value<S> resultLike(Eigen::Index rows, Eigen::Index cols, bool tangent, Eigen::Index columns) {
  Value<S> out;
  out.m = MatX<S>::Zero(rows, cols);
  if constexpr (kTracesTangents<S>) {
    out.has_tangent = tangent;
    if (tangent) out.d = MatX<S>::Zero(rows * cols, columns);
  }
  return out;
}

template <class S> Eigen::Index tangentColumns(const Value<S>& a, const Value<S>& b) {
  return a.has_tangent ? a.d.cols() : b.has_tangent ? b.d.cols() : 0;
}

// f applied entry by entry with broadcasting of a scalar operand; df(a, b, y) gives the
// partials (d y / d a, d y / d b).
template <class S>
Value<S> zipEntries(const Value<S>& a, const Value<S>& b, const char* what, int column,
                    const std::function<S(const S&, const S&)>& f,
                    const std::function<std::pair<S, S>(const S&, const S&, const S&)>& df) {
  const bool same = a.rows() == b.rows() && a.cols() == b.cols();
  if (!same && !a.isScalar() && !b.isScalar())
    throw EvalError(column, std::string(what) + " needs operands of one shape (or a scalar), got " + shapeOf(a) + " and " +
                                shapeOf(b));
  const Value<S>& shape = same || b.isScalar() ? a : b;
  Value<S> out = resultLike<S>(shape.rows(), shape.cols(), a.has_tangent || b.has_tangent, tangentColumns(a, b));
  for (Eigen::Index k = 0; k < out.size(); ++k) {
    const Eigen::Index ka = a.isScalar() && !same ? 0 : k, kb = b.isScalar() && !same ? 0 : k;
    const S& x = a.flat(ka);
    const S& y = b.flat(kb);
    out.flat(k) = f(x, y);
    if (out.has_tangent) {
      const auto [pa, pb] = df(x, y, out.flat(k));
      addTangentRow(out, k, pa, a, ka);
      addTangentRow(out, k, pb, b, kb);
    }
  }
  return out;
}

// f applied to every entry; df(x, y) = d y / d x.
template <class S>
Value<S> mapEntries(const Value<S>& a, const std::function<S(const S&)>& f, const std::function<S(const S&, const S&)>& df) {
  Value<S> out = resultLike<S>(a.rows(), a.cols(), a.has_tangent, a.has_tangent ? a.d.cols() : 0);
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    out.flat(k) = f(a.flat(k));
    if (out.has_tangent) addTangentRow(out, k, df(a.flat(k), out.flat(k)), a, k);
  }
  return out;
}

// a @ b.
template <class S> Value<S> matrixProduct(const Value<S>& a, const Value<S>& b, int column) {
  if (a.cols() != b.rows())
    throw EvalError(column, "'@' needs the left operand's columns to equal the right one's rows, got " + shapeOf(a) +
                                " @ " + shapeOf(b));
  Value<S> out = resultLike<S>(a.rows(), b.cols(), a.has_tangent || b.has_tangent, tangentColumns(a, b));
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    for (Eigen::Index j = 0; j < b.cols(); ++j) {
      S sum(0);
      for (Eigen::Index k = 0; k < a.cols(); ++k) {
        if (isZero(a.m(i, k)) || isZero(b.m(k, j))) continue;
        sum = isZero(sum) ? S(a.m(i, k) * b.m(k, j)) : S(sum + a.m(i, k) * b.m(k, j));
      }
      out.m(i, j) = sum;
      if (!out.has_tangent) continue;
      for (Eigen::Index k = 0; k < a.cols(); ++k) {
        addTangentRow(out, out.at(i, j), b.m(k, j), a, a.at(i, k));
        addTangentRow(out, out.at(i, j), a.m(i, k), b, b.at(k, j));
      }
    }
  return out;
}

// Entries picked from `a`: out entry k is a's entry source[k] (row-major indices).
template <class S> Value<S> gather(const Value<S>& a, Eigen::Index rows, Eigen::Index cols, const std::vector<Eigen::Index>& source) {
  Value<S> out = resultLike<S>(rows, cols, false, 0);
  out.has_tangent = a.has_tangent;
  if (a.has_tangent) out.d.resize(rows * cols, a.d.cols());
  for (Eigen::Index k = 0; k < rows * cols; ++k) {
    out.flat(k) = a.flat(source[k]);
    if (a.has_tangent) out.d.row(k) = a.d.row(source[k]);
  }
  return out;
}

template <class S> Value<S> transposed(const Value<S>& a) {
  std::vector<Eigen::Index> source;
  for (Eigen::Index r = 0; r < a.cols(); ++r)
    for (Eigen::Index c = 0; c < a.rows(); ++c) source.push_back(a.at(c, r));
  return gather(a, a.cols(), a.rows(), source);
}

// The sum of a list of values of one shape, each scaled by a constant.
template <class S> Value<S> scaled(const Value<S>& a, double c) {
  Value<S> out = a;
  out.m *= S(c);
  if (out.has_tangent) out.d *= S(c);
  return out;
}

// Blocks side by side (one row of a matrix literal), or rows stacked.
template <class S> Value<S> concatenate(const std::vector<Value<S>>& parts, bool side_by_side, int column) {
  Eigen::Index rows = 0, cols = 0, columns = 0;
  bool tangent = false;
  for (const Value<S>& p : parts) {
    if (side_by_side ? (rows && p.rows() != rows) : (cols && p.cols() != cols))
      throw EvalError(column, std::string(side_by_side ? "elements side by side (',') need equal rows" : "rows stacked (';') need equal columns") +
                                  ", got " + shapeOf(parts.front()) + " and " + shapeOf(p));
    if (side_by_side) rows = p.rows(), cols += p.cols();
    else cols = p.cols(), rows += p.rows();
    if (p.has_tangent) tangent = true, columns = p.d.cols();
  }
  Value<S> out = resultLike<S>(rows, cols, tangent, columns);
  Eigen::Index offset = 0;
  for (const Value<S>& p : parts) {
    for (Eigen::Index r = 0; r < p.rows(); ++r)
      for (Eigen::Index c = 0; c < p.cols(); ++c) {
        const Eigen::Index orow = side_by_side ? r : r + offset, ocol = side_by_side ? c + offset : c;
        out.m(orow, ocol) = p.m(r, c);
        if (tangent && p.has_tangent) out.d.row(out.at(orow, ocol)) = p.d.row(p.at(r, c));
      }
    offset += side_by_side ? p.cols() : p.rows();
  }
  return out;
}

// Sum of entries of `a` each times weight(k) (a linear map to a scalar).
template <class S> Value<S> weightedSum(const Value<S>& a, const std::function<S(Eigen::Index)>& weight) {
  Value<S> out = resultLike<S>(1, 1, a.has_tangent, a.has_tangent ? a.d.cols() : 0);
  S sum(0);
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    const S w = weight(k);
    if (isZero(w) || isZero(a.flat(k))) {
      addTangentRow(out, 0, w, a, k);
      continue;
    }
    sum = isZero(sum) ? S(w * a.flat(k)) : S(sum + w * a.flat(k));
    addTangentRow(out, 0, w, a, k);
  }
  out.m(0, 0) = sum;
  return out;
}

}  // namespace robodiff::detail
