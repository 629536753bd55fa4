// Inverse of a small symmetric positive-definite matrix by an unpivoted Cholesky
// factorisation: no branches on values, so symbolic scalars trace it unchanged.
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

}  // namespace robodiff
