// Analytic partial derivatives of inverse dynamics: d tau/dq, d tau/dv, d tau/da = M,
// in O(n d) (d: depth of the tree), after Carpentier & Mansard (RSS 2018). Derived here
// in the world frame, with every 6-vector as [linear; angular] and S_c the world-frame
// subspace column of velocity coordinate c, whose joint is J (parent joint p):
//
//   d v_k / d q_c = S_c x (v_k - v_p),  d a_k / d q_c = S_c x (a_k - a_p) - (S_c x v_p) x (v_k - v_p)
//   for every body k supported by J. Summed over a subtree K of J, the forces' derivative
//   is  S_c x* F_K - Y_K xi_c - B_K w_c,  w_c = S_c x v_p,  xi_c = S_c x a_p - w_c x v_p,
//   with Y_K the composite inertia and B_K = sum_k (v_k x*) I_k - I_k (v_k x) + (I_k v_k x-bar*)
//   the composite "Coriolis" matrix (x-bar*: w -> w x* h). Then, for a row i whose joint
//   is in J's subtree (the S_i change cancels the S_c x* F term):
//     d tau_i/d q_c = -(Y_i S_i) . xi_c - (B_i^T S_i) . w_c
//     d tau_i/d v_c =  (B_i^T S_i) . S_c - (Y_i S_i) . zeta_c,  zeta_c = S_c x (v_p + v_J)
//     d tau_i/d a_c =  (Y_i S_i) . S_c
//   and for a row r of a strict ancestor of J: S_r . (S_c x* F_J - Y_J xi_c - B_J w_c),
//   S_r . (B_J S_c - Y_J zeta_c) and S_r . (Y_J S_c).
// Savings in operations (the traced code is what they are for): B_K is never a 6 x 6
// matrix but 15 numbers (CoriolisComposite below: its top-left block is zero, its
// off-diagonal blocks are skew, its bottom-right block symmetric, plus the momentum),
// summed up the tree and applied with cross products; and for a joint of one velocity
// coordinate v_J - v_p is S_c qdot_c, so zeta_c = 2 w_c.
// The q-derivative of a free-flyer is in the tangent space (the golden files'
// convention). Branch-free on values, so symbolic scalars trace it unchanged: this is
// what generated RNEA and ABA Jacobians are built from (core/functions/README.md).
#pragma once

#include <vector>

#include "robodiff/dynamics/crba.hpp"
#include "robodiff/dynamics/rnea.hpp"

namespace robodiff {

namespace detail {

template <class S> S pair(const Motion<S>& m, const Force<S>& f) { return m.linear.dot(f.linear) + m.angular.dot(f.angular); }

// The composite "Coriolis" matrix B_K of a subtree in 15 numbers. For one body,
// X = (v x*) I gives (v x*) I - I (v x) = X + X^T = [0, t^; -t^, Sbr] with
// t = h x omega - m v_lin (h: first moment, so h^ omega^ - omega^ h^ = (h x omega)^) and
// Sbr = -(v^ h^ + h^ v^) + (omega^ I_rot - I_rot omega^) symmetric; the momentum term
// w -> w x* mu adds [0, -mu_l^; -mu_l^, -mu_a^]. These are linear in the body, so a
// subtree's B sums t, Sbr and mu (15 additions per edge instead of 36), and B x and
// B^T x are a few cross products instead of 6 x 6 products.
template <class S> struct CoriolisComposite {
  Vec3<S> t = Vec3<S>::Zero();
  Mat3<S> sbr = Mat3<S>::Zero();  // symmetric; (i, j) and (j, i) are the same value
  Force<S> mu;                    // the subtree's momentum

  CoriolisComposite& operator+=(const CoriolisComposite& o) {
    t += o.t;
    sbr += o.sbr;
    mu += o.mu;
    return *this;
  }
  // B x = [(t - mu_l) x x_a; -(t + mu_l) x x_l + Sbr x_a - mu_a x x_a]
  Force<S> times(const Motion<S>& x) const {
    const Vec3<S> tx = t.cross(x.angular), mx = mu.linear.cross(x.angular);
    return {tx - mx, Vec3<S>(sbr * x.angular) - t.cross(x.linear) - mu.linear.cross(x.linear) - mu.angular.cross(x.angular)};
  }
  // B^T x = [(t + mu_l) x x_a; (mu_l - t) x x_l + Sbr x_a + mu_a x x_a]
  Force<S> transposeTimes(const Motion<S>& x) const {
    const Vec3<S> tx = t.cross(x.angular), mx = mu.linear.cross(x.angular);
    return {tx + mx, Vec3<S>(sbr * x.angular) - t.cross(x.linear) + mu.linear.cross(x.linear) + mu.angular.cross(x.angular)};
  }
};

// One body's B (world frame), from its inertia I, velocity v and momentum mu = I v.
template <class S> CoriolisComposite<S> bodyCoriolis(const InertiaSum<S>& I, const Motion<S>& v, const Force<S>& mu) {
  CoriolisComposite<S> b;
  const Vec3<S>& w = v.angular;
  const Vec3<S>& vl = v.linear;
  b.t = I.h.cross(w) - I.mass * vl;
  // -(v^ h^ + h^ v^) = 2 (v . h) 1 - (h v^T + v h^T)
  const Vec3<S> vh(vl[0] * I.h[0], vl[1] * I.h[1], vl[2] * I.h[2]);
  // omega^ I_rot, whose symmetric part doubled is omega^ I_rot - I_rot omega^
  const Mat3<S> wI = skew(w) * I.rotational;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    b.sbr(i, i) = S(2) * (vh[j] + vh[k]) + S(2) * wI(i, i);
    const S off = (wI(i, j) + wI(j, i)) - (I.h[i] * vl[j] + vl[i] * I.h[j]);
    b.sbr(i, j) = off;
    b.sbr(j, i) = off;
  }
  b.mu = mu;
  return b;
}

}  // namespace detail

namespace detail {

// The world-frame sweep's per-joint quantities: after worldForwardSweep, each body's own
// velocity, acceleration, force, inertia and B; after sumOverSubtrees, oF, oY and oB hold
// the sums over each joint's subtree.
template <class S> struct WorldSweep {
  std::vector<Motion<S>> ov, oa;
  std::vector<Force<S>> oF;
  std::vector<InertiaSum<S>> oY;
  std::vector<CoriolisComposite<S>> oB;
};

template <class S> Motion<S> subspaceColumn(const Data<S>& data, int c) { return Motion<S>::fromVector(data.J.col(c)); }

// Forward: world-frame placements (data.oMi), subspace columns (data.J), velocities,
// accelerations, and each body's force, inertia and B matrix.
template <class S, class Q, class V, class A>
WorldSweep<S> worldForwardSweep(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q,
                                const Eigen::MatrixBase<V>& v, const Eigen::MatrixBase<A>& a) {
  const int n = model.njoints();
  WorldSweep<S> w{std::vector<Motion<S>>(n), std::vector<Motion<S>>(n), std::vector<Force<S>>(n),
                  std::vector<InertiaSum<S>>(n), std::vector<CoriolisComposite<S>>(n)};
  const Motion<S> a0 = gravityAcceleration<S>(model);
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints[j];
    data.liMi[j] = jointPlacement<S>(joint, q);
    data.oMi[j] = joint.parent >= 0 ? data.oMi[joint.parent] * data.liMi[j] : data.liMi[j];
    Motion<S> vrel, arel;
    for (int k = 0; k < joint.nv; ++k) {
      const int c = joint.idx_v + k;
      data.J.col(c) = worldSubspaceColumn(joint, data.oMi[j], k);
      const Motion<S> s = subspaceColumn(data, c);
      vrel += Motion<S>{s.linear * v[c], s.angular * v[c]};
      arel += Motion<S>{s.linear * a[c], s.angular * a[c]};
    }
    const Motion<S> vp = joint.parent >= 0 ? w.ov[joint.parent] : Motion<S>::Zero();
    const Motion<S> ap = joint.parent >= 0 ? w.oa[joint.parent] : a0;
    w.ov[j] = vp + vrel;
    w.oa[j] = ap + arel + w.ov[j].cross(vrel);
    w.oY[j] = worldInertia(model.bodies[j], data.oMi[j]);
    const Force<S> h = w.oY[j] * w.ov[j];
    w.oF[j] = w.oY[j] * w.oa[j] + w.ov[j].cross(h);
    w.oB[j] = bodyCoriolis(w.oY[j], w.ov[j], h);
  }
  return w;
}

// Backward: forces, inertias and B summed over subtrees.
template <class S> void sumOverSubtrees(const Model& model, WorldSweep<S>& w) {
  for (int j = model.njoints() - 1; j > 0; --j) {
    const int p = model.joints[j].parent;
    if (p < 0) continue;
    w.oY[p] += w.oY[j];
    w.oF[p] += w.oF[j];
    w.oB[p] += w.oB[j];
  }
}

// tau_c = S_c . F_J for every velocity coordinate c (J: c's joint), from the subtree sums.
template <class S> VecX<S> jointTorques(const Model& model, const Data<S>& data, const WorldSweep<S>& w) {
  VecX<S> tau(model.nv);
  for (int j = 0; j < model.njoints(); ++j)
    for (int k = 0; k < model.joints[j].nv; ++k) {
      const int c = model.joints[j].idx_v + k;
      tau[c] = pair(subspaceColumn(data, c), w.oF[j]);
    }
  return tau;
}

// The partials from the subtree sums (the formulas at the top of this file).
template <class S>
void rneaPartialsFromSweep(const Model& model, const Data<S>& data, const WorldSweep<S>& w, MatX<S>& dtau_dq,
                           MatX<S>& dtau_dv, MatX<S>& dtau_da) {
  const int n = model.njoints(), nv = model.nv;
  const Motion<S> a0 = gravityAcceleration<S>(model);
  auto column = [&](int c) { return subspaceColumn(data, c); };
  // Per row i: P_i = Y_i S_i and Q_i = B_i^T S_i (B_i, Y_i: composites of i's joint).
  std::vector<Force<S>> P(nv), Qf(nv);
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < model.joints[j].nv; ++k) {
      const int i = model.joints[j].idx_v + k;
      P[i] = w.oY[j] * column(i);
      Qf[i] = w.oB[j].transposeTimes(column(i));
    }
  dtau_dq = MatX<S>::Zero(nv, nv);
  dtau_dv = MatX<S>::Zero(nv, nv);
  dtau_da = MatX<S>::Zero(nv, nv);
  for (int J = 0; J < n; ++J) {
    const Joint& joint = model.joints[J];
    const Motion<S> vp = joint.parent >= 0 ? w.ov[joint.parent] : Motion<S>::Zero();
    const Motion<S> ap = joint.parent >= 0 ? w.oa[joint.parent] : a0;
    const int end = model.subtree_end[J] < n ? model.joints[model.subtree_end[J]].idx_v : nv;
    for (int k = 0; k < joint.nv; ++k) {
      const int c = joint.idx_v + k;
      const Motion<S> s = column(c);
      const Motion<S> wc = s.cross(vp);
      const Motion<S> xi = s.cross(ap) - wc.cross(vp);
      const Motion<S> zeta = joint.nv == 1 ? wc + wc : s.cross(vp + w.ov[J]);
      for (int i = joint.idx_v; i < end; ++i) {
        dtau_dq(i, c) = -pair(xi, P[i]) - pair(wc, Qf[i]);
        dtau_dv(i, c) = pair(s, Qf[i]) - pair(zeta, P[i]);
        dtau_da(i, c) = pair(s, P[i]);
      }
      if (joint.parent < 0) continue;
      const Force<S> G = s.cross(w.oF[J]) - w.oY[J] * xi - w.oB[J].times(wc);
      const Force<S> H = w.oB[J].times(s) - w.oY[J] * zeta;
      const Force<S> YS = w.oY[J] * s;
      for (int r_joint = joint.parent; r_joint >= 0; r_joint = model.joints[r_joint].parent)
        for (int kr = 0; kr < model.joints[r_joint].nv; ++kr) {
          const int r = model.joints[r_joint].idx_v + kr;
          const Motion<S> sr = column(r);
          dtau_dq(r, c) = pair(sr, G);
          dtau_dv(r, c) = pair(sr, H);
          dtau_da(r, c) = pair(sr, YS);
        }
    }
  }
}

}  // namespace detail

// The three nv x nv partials of rnea(model, data, q, v, a), and tau itself in data.tau
// from the same sweep (tau_c = S_c . F_J, F_J the world-frame force on J's subtree), so a
// caller wanting value and derivatives needs no second RNEA.
template <class S, class Q, class V, class A>
void computeRneaDerivatives(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q,
                            const Eigen::MatrixBase<V>& v, const Eigen::MatrixBase<A>& a, MatX<S>& dtau_dq,
                            MatX<S>& dtau_dv, MatX<S>& dtau_da) {
  detail::WorldSweep<S> w = detail::worldForwardSweep(model, data, q, v, a);
  detail::sumOverSubtrees(model, w);
  data.tau = detail::jointTorques(model, data, w);
  detail::rneaPartialsFromSweep(model, data, w, dtau_dq, dtau_dv, dtau_da);
}

}  // namespace robodiff
