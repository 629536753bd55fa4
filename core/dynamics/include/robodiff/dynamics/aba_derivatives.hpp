// Forward dynamics and what its derivatives are made of, from one world-frame sweep:
// ddq = ABA(q, v, tau), RNEA's partials at a = ddq and the tree factors of M, so that
//   d ddq/d(q, v) = -M^-1 d rnea/d(q, v) at a = ddq,   d ddq/d tau = M^-1.
// The sweep of rnea_derivatives.hpp runs first with a = 0: its subtree forces give
// nle = RNEA(q, v, 0) and its subtree inertias M, so ddq = M^-1 (tau - nle) by the
// factors. Then the acceleration's part is added: each body's acceleration gains
// acc_j = acc_parent + S_j ddq_j (the sweep's acceleration is linear in a, with no
// product of a and v), its force Y_j acc_j, summed up the tree. The partials then come
// from the completed sweep, as for RNEA. Tracing ABA itself for ddq as well costs more
// than the solve and these additions (docs/code-generation.md). Branch-free on values.
#pragma once

#include <vector>

#include "robodiff/dynamics/minv.hpp"
#include "robodiff/dynamics/rnea_derivatives.hpp"

namespace robodiff {

template <class S> struct AbaDerivativeTerms {
  VecX<S> ddq;
  MatX<S> dtau_dq, dtau_dv;  // RNEA's partials at a = ddq
  MatX<S> mass_factors;      // M = L^T D L as factorizeMassMatrix leaves it (lower triangle)
};

namespace detail {

// M's lower triangle from the subtree inertias: M(i, c) = S_c . Y_I S_i for i >= c in the
// subtree of c's joint (I: i's joint); zero elsewhere.
template <class S> MatX<S> massMatrixFromSweep(const Model& model, const Data<S>& data, const WorldSweep<S>& w) {
  const int n = model.njoints(), nv = model.nv;
  std::vector<Force<S>> P(static_cast<std::size_t>(nv));
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < model.joints[j].nv; ++k) {
      const int i = model.joints[j].idx_v + k;
      P[i] = w.oY[j] * subspaceColumn(data, i);
    }
  MatX<S> M = MatX<S>::Zero(nv, nv);
  for (int J = 0; J < n; ++J) {
    const Joint& joint = model.joints[J];
    const int end = model.subtree_end[J] < n ? model.joints[model.subtree_end[J]].idx_v : nv;
    for (int k = 0; k < joint.nv; ++k) {
      const int c = joint.idx_v + k;
      for (int i = c; i < end; ++i) M(i, c) = pair(subspaceColumn(data, c), P[i]);
    }
  }
  return M;
}

// Adds to the sweep (run with a = 0) the part of accelerations and forces that ddq makes.
template <class S> void addAccelerationPart(const Model& model, const Data<S>& data, const VecX<S>& ddq,
                                            const std::vector<InertiaSum<S>>& body_inertia, WorldSweep<S>& w) {
  const int n = model.njoints();
  std::vector<Motion<S>> acc(static_cast<std::size_t>(n));
  std::vector<Force<S>> force(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints[j];
    if (joint.parent >= 0) acc[j] = acc[joint.parent];
    for (int k = 0; k < joint.nv; ++k) {
      const Motion<S> s = subspaceColumn(data, joint.idx_v + k);
      acc[j] += Motion<S>{s.linear * ddq[joint.idx_v + k], s.angular * ddq[joint.idx_v + k]};
    }
    w.oa[j] += acc[j];
    force[j] = body_inertia[j] * acc[j];
  }
  for (int j = n - 1; j > 0; --j)
    if (model.joints[j].parent >= 0) force[model.joints[j].parent] += force[j];
  for (int j = 0; j < n; ++j) w.oF[j] += force[j];
}

}  // namespace detail

template <class S, class Q, class V, class T>
AbaDerivativeTerms<S> computeAbaDerivativeTerms(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q,
                                                const Eigen::MatrixBase<V>& v, const Eigen::MatrixBase<T>& tau) {
  detail::WorldSweep<S> w = detail::worldForwardSweep(model, data, q, v, VecX<S>::Zero(model.nv));
  const std::vector<InertiaSum<S>> body_inertia = w.oY;
  detail::sumOverSubtrees(model, w);
  AbaDerivativeTerms<S> out;
  out.mass_factors = detail::massMatrixFromSweep(model, data, w);
  const std::vector<int> lambda = dofParents(model);
  factorizeMassMatrix(lambda, out.mass_factors);
  out.ddq = solveWithFactors(lambda, out.mass_factors, VecX<S>(tau - detail::jointTorques(model, data, w)));
  detail::addAccelerationPart(model, data, out.ddq, body_inertia, w);
  MatX<S> dtau_da;  // M again: its factors are out.mass_factors
  detail::rneaPartialsFromSweep(model, data, w, out.dtau_dq, out.dtau_dv, dtau_da);
  return out;
}

}  // namespace robodiff
