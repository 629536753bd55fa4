// The math functions of the expression language (elementwise, reductions, vector
// algebra), on Value<S> with their derivative rules. callMath returns false for a name
// that is not one of them (a model primitive, or unknown).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "user_operations.hpp"

namespace robodiff::detail {

inline const std::vector<std::string>& mathFunctionNames() {
  static const std::vector<std::string> names = {
      "sin", "cos", "tan", "asin", "acos", "atan", "exp", "log", "sqrt", "tanh", "abs", "softplus", "atan2", "pow",
      "min", "max", "select", "sum", "sumsq", "norm", "dot", "cross", "skew", "transpose", "eye", "zeros"};
  return names;
}

template <class S> S selectEntry(const S& c, const S& a, const S& b) { return math::selectPositive(c, a, b); }

template <class S> Value<S> unaryMath(const std::string& name, const Value<S>& x) {
  using std::abs, std::acos, std::asin, std::atan, std::cos, std::exp, std::log, std::sin, std::sqrt, std::tan, std::tanh;
  using std::max;
  using F = std::function<S(const S&)>;
  using D = std::function<S(const S&, const S&)>;
  const S one(1.0);
  if (name == "sin") return mapEntries<S>(x, F([](const S& a) { return sin(a); }), D([](const S& a, const S&) { return cos(a); }));
  if (name == "cos") return mapEntries<S>(x, F([](const S& a) { return cos(a); }), D([](const S& a, const S&) { return S(-sin(a)); }));
  if (name == "tan") return mapEntries<S>(x, F([](const S& a) { return tan(a); }), D([one](const S&, const S& y) { return S(one + y * y); }));
  if (name == "asin") return mapEntries<S>(x, F([](const S& a) { return asin(a); }), D([one](const S& a, const S&) { return S(one / sqrt(one - a * a)); }));
  if (name == "acos") return mapEntries<S>(x, F([](const S& a) { return acos(a); }), D([one](const S& a, const S&) { return S(-one / sqrt(one - a * a)); }));
  if (name == "atan") return mapEntries<S>(x, F([](const S& a) { return atan(a); }), D([one](const S& a, const S&) { return S(one / (one + a * a)); }));
  if (name == "exp") return mapEntries<S>(x, F([](const S& a) { return exp(a); }), D([](const S&, const S& y) { return y; }));
  if (name == "log") return mapEntries<S>(x, F([](const S& a) { return log(a); }), D([one](const S& a, const S&) { return S(one / a); }));
  if (name == "sqrt") return mapEntries<S>(x, F([](const S& a) { return sqrt(a); }), D([](const S&, const S& y) { return S(S(0.5) / y); }));
  if (name == "tanh") return mapEntries<S>(x, F([](const S& a) { return tanh(a); }), D([one](const S&, const S& y) { return S(one - y * y); }));
  if (name == "abs")
    return mapEntries<S>(x, F([](const S& a) { return abs(a); }),
                         D([one](const S& a, const S&) { return selectEntry<S>(a, one, S(-1.0)); }));
  // softplus(a) = log(1 + exp(a)) written so that it never overflows; its slope is the
  // logistic function.
  return mapEntries<S>(x, F([one](const S& a) { return S(max(a, S(0.0)) + log(one + exp(-abs(a)))); }),
                       D([one](const S& a, const S&) { return S(one / (one + exp(-a))); }));
}

template <class S> Value<S> binaryMath(const std::string& name, const Value<S>& a, const Value<S>& b, int column) {
  using std::atan2, std::log, std::max, std::min, std::pow;
  using F = std::function<S(const S&, const S&)>;
  using D = std::function<std::pair<S, S>(const S&, const S&, const S&)>;
  const S one(1.0), zero(0.0);
  const std::string what = name + "()";
  if (name == "atan2")
    return zipEntries<S>(a, b, what.c_str(), column, F([](const S& y, const S& x) { return atan2(y, x); }),
                         D([](const S& y, const S& x, const S&) {
                           const S r = x * x + y * y;
                           return std::pair<S, S>(x / r, -y / r);
                         }));
  if (name == "pow")
    return zipEntries<S>(a, b, what.c_str(), column, F([](const S& x, const S& e) { return pow(x, e); }),
                         D([one, zero](const S& x, const S& e, const S& y) {
                           const S de = isZero(e) ? zero : S(e * pow(x, e - one));
                           return std::pair<S, S>(de, y * log(x));
                         }));
  // min / max: the tangent of the side chosen (at a tie, the second's, as the graph's rules).
  const bool is_min = name == "min";
  return zipEntries<S>(a, b, what.c_str(), column,
                       F([is_min](const S& x, const S& y) { return is_min ? min(x, y) : max(x, y); }),
                       D([is_min, one, zero](const S& x, const S& y, const S&) {
                         const S first = selectEntry<S>(is_min ? S(y - x) : S(x - y), one, zero);
                         return std::pair<S, S>(first, one - first);
                       }));
}

template <class S> void expectVector3(const Value<S>& v, const std::string& name, int column) {
  if (v.rows() != 3 || v.cols() != 1) throw EvalError(column, name + "() takes 3-vectors, got " + shapeOf(v));
}

template <class S> Value<S> crossProduct(const Value<S>& a, const Value<S>& b, int column) {
  expectVector3(a, "cross", column);
  expectVector3(b, "cross", column);
  Value<S> out = resultLike<S>(3, 1, a.has_tangent || b.has_tangent, tangentColumns(a, b));
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    out.m(i, 0) = a.m(j, 0) * b.m(k, 0) - a.m(k, 0) * b.m(j, 0);
    addTangentRow(out, i, b.m(k, 0), a, j);
    addTangentRow(out, i, S(-b.m(j, 0)), a, k);
    addTangentRow(out, i, a.m(j, 0), b, k);
    addTangentRow(out, i, S(-a.m(k, 0)), b, j);
  }
  return out;
}

template <class S> Value<S> skewMatrix(const Value<S>& a, int column) {
  expectVector3(a, "skew", column);
  // [0 -z y; z 0 -x; -y x 0]: entries are +-a's entries, as a gather and sign flips.
  const Value<S> neg = scaled(a, -1.0);
  const Value<S> zero = resultLike<S>(1, 1, false, 0);
  std::vector<Value<S>> rows;
  auto entry = [&](const Value<S>& v, int k) { return gather(v, 1, 1, {k}); };
  rows.push_back(concatenate<S>({zero, entry(neg, 2), entry(a, 1)}, true, column));
  rows.push_back(concatenate<S>({entry(a, 2), zero, entry(neg, 0)}, true, column));
  rows.push_back(concatenate<S>({entry(neg, 1), entry(a, 0), zero}, true, column));
  for (Value<S>& r : rows)
    if (!r.has_tangent && (a.has_tangent)) {
      r.has_tangent = true;
      r.d = MatX<S>::Zero(3, a.d.cols());
    }
  return concatenate<S>(rows, false, column);
}

// select(c, a, b): a where c > 0, else b, entry by entry, without a branch in the code;
// the tangent is the chosen side's. Any operand may be a scalar.
template <class S> Value<S> selectValues(const Value<S>& c, const Value<S>& a, const Value<S>& b, int column) {
  const Value<S>* shape = &c;
  for (const Value<S>* v : {&a, &b})
    if (!v->isScalar()) shape = v;
  for (const Value<S>* v : {&c, &a, &b})
    if (!v->isScalar() && (v->rows() != shape->rows() || v->cols() != shape->cols()))
      throw EvalError(column, "select() needs operands of one shape (or scalars), got " + shapeOf(*v) + " and " + shapeOf(*shape));
  Value<S> out = resultLike<S>(shape->rows(), shape->cols(), a.has_tangent || b.has_tangent, tangentColumns(a, b));
  auto pick = [](const Value<S>& v, Eigen::Index k) { return v.isScalar() ? Eigen::Index(0) : k; };
  for (Eigen::Index k = 0; k < out.size(); ++k) {
    const S& cond = c.flat(pick(c, k));
    out.flat(k) = selectEntry<S>(cond, a.flat(pick(a, k)), b.flat(pick(b, k)));
    if (!out.has_tangent) continue;
    for (Eigen::Index j = 0; j < out.d.cols(); ++j) {
      const S da = a.has_tangent ? a.d(pick(a, k), j) : S(0.0), db = b.has_tangent ? b.d(pick(b, k), j) : S(0.0);
      if (!(isZero(da) && isZero(db))) out.d(k, j) = selectEntry<S>(cond, da, db);
    }
  }
  return out;
}

// Calls a math function; false when `name` is none of them.
template <class S>
bool callMath(const std::string& name, const std::vector<Value<S>>& args, int column, Value<S>& out) {
  const auto& names = mathFunctionNames();
  if (std::find(names.begin(), names.end(), name) == names.end()) return false;
  auto arity = [&](std::size_t n) {
    if (args.size() != n)
      throw EvalError(column, name + "() takes " + std::to_string(n) + " argument" + (n == 1 ? "" : "s") + ", got " +
                                  std::to_string(args.size()));
  };
  auto times = [](const Value<S>& a, const Value<S>& b, int col) {
    return zipEntries<S>(a, b, "'*'", col, [](const S& x, const S& y) { return S(x * y); },
                         [](const S& x, const S& y, const S&) { return std::pair<S, S>(y, x); });
  };
  auto sum = [](const Value<S>& a) { return weightedSum<S>(a, [](Eigen::Index) { return S(1.0); }); };
  if (name == "atan2" || name == "pow" || name == "min" || name == "max") {
    arity(2);
    out = binaryMath(name, args[0], args[1], column);
  } else if (name == "select") {
    arity(3);
    out = selectValues(args[0], args[1], args[2], column);
  } else if (name == "sum" || name == "sumsq" || name == "norm") {
    arity(1);
    out = name == "sum" ? sum(args[0]) : sum(times(args[0], args[0], column));
    if (name == "norm") out = unaryMath<S>("sqrt", out);
  } else if (name == "dot") {
    arity(2);
    if (args[0].size() != args[1].size() || args[0].cols() != args[1].cols())
      throw EvalError(column, "dot() needs two vectors of one size, got " + shapeOf(args[0]) + " and " + shapeOf(args[1]));
    out = sum(times(args[0], args[1], column));
  } else if (name == "cross") {
    arity(2);
    out = crossProduct(args[0], args[1], column);
  } else if (name == "skew") {
    arity(1);
    out = skewMatrix(args[0], column);
  } else if (name == "transpose") {
    arity(1);
    out = transposed(args[0]);
  } else if (name == "eye" || name == "zeros") {
    throw EvalError(column, name + "() is evaluated from constant sizes by the evaluator");
  } else {
    arity(1);
    out = unaryMath<S>(name, args[0]);
  }
  return true;
}

}  // namespace robodiff::detail
