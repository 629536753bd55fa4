// Inverse of a small symmetric positive-definite matrix by an unpivoted Cholesky
// factorisation, and a solve with one by an unpivoted LDL^T factorisation: no branches on
// values, so symbolic scalars trace them unchanged.
#pragma once

#include "robodiff/spatial/math.hpp"

namespace robodiff {

template <class S, class M> M inverseSymmetricPositiveDefinite(const M& a) {
  const Eigen::Index n = a.rows();
  if (n == 1) {
    M out(1, 1);
    out(0, 0) = S(1) / a(0, 0);
    return out;
  }
  // a = L L^T, then a^-1 = L^-T L^-1.
  M L = M::Zero(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    S d = a(j, j);
    for (Eigen::Index k = 0; k < j; ++k) d -= L(j, k) * L(j, k);
    L(j, j) = math::sqrt(d);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      S s = a(i, j);
      for (Eigen::Index k = 0; k < j; ++k) s -= L(i, k) * L(j, k);
      L(i, j) = s / L(j, j);
    }
  }
  M Linv = M::Zero(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    Linv(j, j) = S(1) / L(j, j);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      S s = S(0);
      for (Eigen::Index k = j; k < i; ++k) s -= L(i, k) * Linv(k, j);
      Linv(i, j) = s / L(i, i);
    }
  }
  return Linv.transpose() * Linv;
}

// x = a^-1 b by a = L D L^T (L unit lower triangular): one division per pivot and no
// square root, so a chain of pivots is a division and multiply-adds each, and the
// substitutions are multiply-adds only. Where only a^-1 b is needed this is a far
// shorter critical path than inverseSymmetricPositiveDefinite's (a floating base's
// root solve in ABA).
template <class S, class M, class V> V solveSymmetricPositiveDefinite(const M& a, const V& b) {
  const Eigen::Index n = a.rows();
  M L = M::Zero(n, n);  // strictly lower part: L; W below holds L(i, j) d_j
  M W = M::Zero(n, n);
  V dinv(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    S d = a(j, j);
    for (Eigen::Index k = 0; k < j; ++k) d -= W(j, k) * L(j, k);
    dinv[j] = S(1) / d;
    for (Eigen::Index i = j + 1; i < n; ++i) {
      S w = a(i, j);
      for (Eigen::Index k = 0; k < j; ++k) w -= W(i, k) * L(j, k);
      W(i, j) = w;
      L(i, j) = w * dinv[j];
    }
  }
  V x(n);
  for (Eigen::Index i = 0; i < n; ++i) {  // L y = b
    S y = b[i];
    for (Eigen::Index k = 0; k < i; ++k) y -= L(i, k) * x[k];
    x[i] = y;
  }
  for (Eigen::Index i = n - 1; i >= 0; --i) {  // D L^T x = y
    S s = x[i] * dinv[i];
    for (Eigen::Index k = i + 1; k < n; ++k) s -= L(k, i) * x[k];
    x[i] = s;
  }
  return x;
}

}  // namespace robodiff
