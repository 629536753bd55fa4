// Scalar math customisation point.
//
// Every algorithm in core/ calls math through these functions, never std:: directly,
// so that a non-double scalar (the symbolic scalar of core/symbolic, an AD type)
// provides its own sin/cos/... by argument-dependent lookup, and the algorithms run
// unchanged on it. Nothing here branches on a value.
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace robodiff::math {

template <class S> inline S sin(const S& x) { using std::sin; return sin(x); }
template <class S> inline S cos(const S& x) { using std::cos; return cos(x); }
template <class S> inline S sqrt(const S& x) { using std::sqrt; return sqrt(x); }

// The constant c as a scalar of type S (for a symbolic scalar: a constant node).
template <class S> inline S constant(double c) { return S(c); }

namespace detail {
inline double selectPositive(double condition, double if_positive, double otherwise) {
  return condition > 0 ? if_positive : otherwise;
}
}  // namespace detail

// condition > 0 ? if_positive : otherwise, both already evaluated; a symbolic scalar
// provides its own branch-free selectPositive (found by argument-dependent lookup).
template <class S> inline S selectPositive(const S& condition, const S& if_positive, const S& otherwise) {
  using detail::selectPositive;
  return selectPositive(condition, if_positive, otherwise);
}

}  // namespace robodiff::math

namespace robodiff {

template <class S> using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S> using Mat3 = Eigen::Matrix<S, 3, 3>;
template <class S> using Vec6 = Eigen::Matrix<S, 6, 1>;
template <class S> using Mat6 = Eigen::Matrix<S, 6, 6>;
template <class S> using Matrix6X = Eigen::Matrix<S, 6, Eigen::Dynamic>;
template <class S> using VecX = Eigen::Matrix<S, Eigen::Dynamic, 1>;
template <class S> using MatX = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;

// The cross-product matrix: skew(a) * b == a.cross(b).
template <class S> inline Mat3<S> skew(const Vec3<S>& a) {
  Mat3<S> m;
  m << S(0), -a.z(), a.y(),
       a.z(), S(0), -a.x(),
       -a.y(), a.x(), S(0);
  return m;
}

}  // namespace robodiff
