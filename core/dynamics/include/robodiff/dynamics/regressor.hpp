// Joint-torque regressor: tau = Y(q, v, a) * pi, linear in the inertial parameters.
//
// pi stacks 10 parameters per joint, in joint order, for the composite body the joint
// moves (every link fixed to it merged), expressed in the joint frame, in Pinocchio's
// order: [m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz], with I the
// rotational inertia about the joint frame's origin (Inertia::parameters()).
// Gravity is included, as in RNEA.
#pragma once

#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/kinematics.hpp"
#include "robodiff/dynamics/rnea.hpp"
#include "robodiff/spatial/inertia.hpp"

namespace robodiff {

// The 6 x 10 matrix Psi with I * a + v x* (I * v) = Psi(v, a) * pi for any body.
template <class S> Eigen::Matrix<S, 6, 10> bodyRegressor(const Motion<S>& v, const Motion<S>& a) {
  const Vec3<S>& vl = v.linear;
  const Vec3<S>& w = v.angular;
  const Vec3<S>& al = a.linear;
  const Vec3<S>& aw = a.angular;
  Eigen::Matrix<S, 6, 10> psi = Eigen::Matrix<S, 6, 10>::Zero();
  // Mass.
  psi.template block<3, 1>(0, 0) = al + w.cross(vl);
  // First moment h = m c.
  Mat3<S> wx = skew<S>(w);
  psi.template block<3, 3>(0, 1) = skew<S>(aw) + wx * wx;
  psi.template block<3, 3>(3, 1) = skew<S>(Vec3<S>(vl.cross(w))) - skew<S>(al);
  // Rotational inertia about the origin: I x = L(x) [xx xy yy xz yz zz].
  auto L = [](const Vec3<S>& x) {
    Eigen::Matrix<S, 3, 6> l = Eigen::Matrix<S, 3, 6>::Zero();
    l(0, 0) = x[0]; l(0, 1) = x[1]; l(0, 3) = x[2];
    l(1, 1) = x[0]; l(1, 2) = x[1]; l(1, 4) = x[2];
    l(2, 3) = x[0]; l(2, 4) = x[1]; l(2, 5) = x[2];
    return l;
  };
  psi.template block<3, 6>(3, 4) = L(aw) + wx * L(w);
  return psi;
}

// Y (nv x 10 njoints) at (q, v, a).
template <class S, class Q, class V, class A>
MatX<S> jointTorqueRegressor(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q,
                             const Eigen::MatrixBase<V>& v, const Eigen::MatrixBase<A>& a) {
  detail::accelerationPass(model, data, q, v, a, gravityAcceleration<S>(model));
  MatX<S> Y = MatX<S>::Zero(model.nv, 10 * model.njoints());
  for (int j = 0; j < model.njoints(); ++j) {
    Eigen::Matrix<S, 6, 10> F = bodyRegressor(data.v[j], data.a[j]);
    for (int i = j; i >= 0; i = model.joints[i].parent) {
      const Joint& joint = model.joints[i];
      for (int col = 0; col < 10; ++col) {
        Force<S> f{F.template block<3, 1>(0, col), F.template block<3, 1>(3, col)};
        for (int k = 0; k < joint.nv; ++k) Y(joint.idx_v + k, 10 * j + col) = projectForce<S>(joint, f, k);
        if (joint.parent >= 0) {
          Force<S> up = data.liMi[i].act(f);
          F.template block<3, 1>(0, col) = up.linear;
          F.template block<3, 1>(3, col) = up.angular;
        }
      }
    }
  }
  return Y;
}

// pi for the whole model (10 per joint, the order above).
inline Eigen::VectorXd inertialParameters(const Model& model) {
  Eigen::VectorXd pi(10 * model.njoints());
  for (int j = 0; j < model.njoints(); ++j) pi.segment<10>(10 * j) = model.bodies[j].parameters();
  return pi;
}

}  // namespace robodiff
