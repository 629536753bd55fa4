// The inverse of the joint-space mass matrix, M(q)^-1, by a factorisation that follows
// the kinematic tree (Featherstone, RBDA section 6.5): M = L^T D L with L unit lower
// triangular, nonzero only where a column's dof is an ancestor of the row's dof, so
// factorising and solving cost O(n d) per column (d: depth) instead of O(n^2), and the
// zeros are never touched. Branch-free on values: symbolic scalars trace it unchanged.
#pragma once

#include <optional>
#include <vector>

#include "robodiff/dynamics/crba.hpp"

namespace robodiff {

// For each velocity coordinate, the coordinate before it on the path to the root (the
// previous one of the same joint, or the last one of the parent joint), or -1.
inline std::vector<int> dofParents(const Model& model) {
  std::vector<int> parent(static_cast<std::size_t>(model.nv), -1);
  for (const Joint& joint : model.joints)
    for (int k = 0; k < joint.nv; ++k) {
      int p = -1;
      if (k > 0) {
        p = joint.idx_v + k - 1;
      } else if (joint.parent >= 0) {
        const Joint& up = model.joints[joint.parent];
        p = up.idx_v + up.nv - 1;
      }
      parent[static_cast<std::size_t>(joint.idx_v + k)] = p;
    }
  return parent;
}

// Overwrites the symmetric M with its factors: D on the diagonal, L strictly below
// (the entries of L that are structurally zero are left as they were).
template <class S> void factorizeMassMatrix(const std::vector<int>& lambda, MatX<S>& M) {
  for (int k = static_cast<int>(M.rows()) - 1; k >= 0; --k) {
    for (int i = lambda[k]; i >= 0; i = lambda[i]) {
      const S a = M(k, i) / M(k, k);
      for (int j = i; j >= 0; j = lambda[j]) M(i, j) -= a * M(k, j);
      M(k, i) = a;
    }
  }
}

// M^-1 (nv x nv, symmetric), with M from crba (the form the scalar picks, or `frame`:
// CrbaFrame::World where the trace has the world placements already); data.M holds the
// factors.
template <class S, class Q>
MatX<S> computeMinverse(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q,
                        std::optional<CrbaFrame> frame = std::nullopt) {
  if (frame) crba(model, data, q, *frame);
  else crba(model, data, q);
  MatX<S>& LD = data.M;  // only the lower triangle is read and written
  const std::vector<int> lambda = dofParents(model);
  factorizeMassMatrix(lambda, LD);
  const int n = model.nv;
  MatX<S> Minv(n, n);
  VecX<S> x(n);
  for (int col = 0; col < n; ++col) {
    // Solve L^T D L x = e_col. Only the lower triangle (rows >= col) is computed; the
    // matrix is symmetric.
    x.setZero();
    x[col] = S(1);
    for (int i = n - 1; i >= 0; --i)  // L^T y = e: y = L^-T e
      for (int j = lambda[i]; j >= 0; j = lambda[j]) x[j] -= LD(i, j) * x[i];
    for (int i = 0; i < n; ++i) x[i] /= LD(i, i);
    for (int i = 0; i < n; ++i)  // L x = y
      for (int j = lambda[i]; j >= 0; j = lambda[j]) x[i] -= LD(i, j) * x[j];
    for (int r = col; r < n; ++r) Minv(r, col) = Minv(col, r) = x[r];
  }
  return Minv;
}

}  // namespace robodiff
