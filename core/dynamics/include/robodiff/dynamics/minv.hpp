// The inverse of the joint-space mass matrix, M(q)^-1, by a factorisation that follows
// the kinematic tree (Featherstone, RBDA section 6.5): M = L^T D L with L unit lower
// triangular, nonzero only where a column's dof is an ancestor of the row's dof, so
// factorising and solving cost O(n d) per column (d: depth) instead of O(n^2), and the
// zeros are never touched. Branch-free on values: symbolic scalars trace it unchanged.
#pragma once

#include <algorithm>
#include <optional>
#include <vector>

#include "robodiff/dynamics/crba.hpp"
#include "robodiff/dynamics/rnea.hpp"

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
// (the entries of L that are structurally zero are left as they were). Each pivot is
// inverted once and its row multiplied: one division per pivot, not one per entry of L
// (the solve and the inverse need the same 1 / D_k, so a trace shares it).
template <class S> void factorizeMassMatrix(const std::vector<int>& lambda, MatX<S>& M) {
  for (int k = static_cast<int>(M.rows()) - 1; k >= 0; --k) {
    const S inverse_pivot = S(1) / M(k, k);
    for (int i = lambda[k]; i >= 0; i = lambda[i]) {
      const S a = M(k, i) * inverse_pivot;
      for (int j = i; j >= 0; j = lambda[j]) M(i, j) -= a * M(k, j);
      M(k, i) = a;
    }
  }
}

// x = M^-1 b by the factors: L^T y = b, z = D^-1 y, then L x = z.
template <class S> VecX<S> solveWithFactors(const std::vector<int>& lambda, const MatX<S>& LD, VecX<S> x) {
  const int n = static_cast<int>(x.size());
  for (int i = n - 1; i >= 0; --i)
    for (int j = lambda[i]; j >= 0; j = lambda[j]) x[j] -= LD(i, j) * x[i];
  for (int i = 0; i < n; ++i) x[i] *= S(1) / LD(i, i);
  for (int i = 0; i < n; ++i)
    for (int j = lambda[i]; j >= 0; j = lambda[j]) x[i] -= LD(i, j) * x[j];
  return x;
}

// N = L^-1 for the unit lower triangular L of the factors: N has L's sparsity (row i
// over i's strict ancestors; the unit diagonal is implied, the rest zero). From L N = I,
// N(i, j) = -L(i, j) - sum over k strictly between j and i on their path of L(i, k) N(k, j).
template <class S> MatX<S> inverseUnitFactor(const std::vector<int>& lambda, const MatX<S>& LD) {
  const int n = static_cast<int>(LD.rows());
  MatX<S> N = MatX<S>::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = lambda[i]; j >= 0; j = lambda[j]) {
      S sum = LD(i, j);
      for (int k = lambda[i]; k != j; k = lambda[k]) sum += LD(i, k) * N(k, j);
      N(i, j) = -sum;
    }
  return N;
}

// M^-1 = N D^-1 N^T: M^-1(r, c) sums N(r, k) N(c, k) / D_k over the common ancestors k of
// r and c (themselves included), so a pair on different branches costs the depth of
// their common ancestor, not the depth of its row as a forward substitution does.
template <class S> MatX<S> inverseFromFactors(const std::vector<int>& lambda, const MatX<S>& LD) {
  const int n = static_cast<int>(LD.rows());
  const MatX<S> N = inverseUnitFactor(lambda, LD);
  auto unit = [&](int r, int k) { return r == k ? S(1) : N(r, k); };
  MatX<S> Minv(n, n);
  std::vector<S> inverse_diagonal, scaled(static_cast<std::size_t>(n));  // scaled: N(c, k) / D_k on c's path
  for (int k = 0; k < n; ++k) inverse_diagonal.push_back(S(1) / LD(k, k));
  std::vector<char> on_path(static_cast<std::size_t>(n));
  for (int c = 0; c < n; ++c) {
    std::fill(on_path.begin(), on_path.end(), 0);
    for (int k = c; k >= 0; k = lambda[k]) {
      scaled[k] = k == c ? inverse_diagonal[k] : N(c, k) * inverse_diagonal[k];
      on_path[k] = 1;
    }
    for (int r = c; r < n; ++r) {  // the lower triangle; M^-1 is symmetric
      int k = r;
      while (k >= 0 && !on_path[k]) k = lambda[k];  // the deepest common ancestor
      S sum = S(0);  // stays 0 where r and c are on separate trees (chains fixed to the world)
      for (; k >= 0; k = lambda[k]) sum += unit(r, k) * scaled[k];
      Minv(r, c) = Minv(c, r) = sum;
    }
  }
  return Minv;
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
  return inverseFromFactors(lambda, LD);
}

// Forward dynamics without articulated inertias: ddq = M^-1 (tau - nle), nle = RNEA(q, v, 0),
// M from crba, by the tree factors. Traced, it is smaller than ABA where M's composite
// inertias fold well (fixed bases, small robots), larger on the free-flying Talos
// (docs/code-generation.md); the function builder builds both and keeps the smaller.
template <class S, class Q, class V, class T>
VecX<S> forwardDynamicsByFactors(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q,
                                 const Eigen::MatrixBase<V>& v, const Eigen::MatrixBase<T>& tau) {
  const VecX<S> bias = tau - nonLinearEffects(model, data, q, v);
  MatX<S> LD = crba(model, data, q);
  const std::vector<int> lambda = dofParents(model);
  factorizeMassMatrix(lambda, LD);
  return solveWithFactors(lambda, LD, bias);
}

}  // namespace robodiff
