// Configuration-space operations: the neutral configuration, q (+) v (integrate on the
// configuration manifold: for the free-flyer the SE(3) exponential in the base frame,
// for the other joints plain addition), and random configurations within limits.
#pragma once

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "robodiff/model/model.hpp"

namespace robodiff {

inline Eigen::VectorXd neutralConfiguration(const Model& model) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model.nq);
  for (const Joint& j : model.joints)
    if (j.type == JointType::FreeFlyer) q[j.idx_q + 6] = 1.0;  // identity quaternion (w last)
  return q;
}

// SE(3) exponential of a twist [linear; angular] (the motion after unit time).
inline SE3<double> exp6(const Eigen::Matrix<double, 6, 1>& twist) {
  const Eigen::Vector3d vl = twist.head<3>(), w = twist.tail<3>();
  const double theta = w.norm();
  const Eigen::Matrix3d wx = skew<double>(w);
  double a, b, c;  // R = I + a wx + b wx^2, V = I + b wx + c wx^2
  if (theta < 1e-6) {
    a = 1 - theta * theta / 6;
    b = 0.5 - theta * theta / 24;
    c = 1.0 / 6 - theta * theta / 120;
  } else {
    a = std::sin(theta) / theta;
    b = (1 - std::cos(theta)) / (theta * theta);
    c = (theta - std::sin(theta)) / (theta * theta * theta);
  }
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  return {I + a * wx + b * wx * wx, (I + b * wx + c * wx * wx) * vl};
}

inline Eigen::VectorXd integrate(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  Eigen::VectorXd out = q;
  for (const Joint& j : model.joints) {
    if (j.type != JointType::FreeFlyer) {
      out[j.idx_q] = q[j.idx_q] + v[j.idx_v];
      continue;
    }
    Eigen::Quaterniond quat(q[j.idx_q + 6], q[j.idx_q + 3], q[j.idx_q + 4], q[j.idx_q + 5]);
    SE3<double> m{quat.toRotationMatrix(), q.segment<3>(j.idx_q)};
    SE3<double> moved = m * exp6(v.segment<6>(j.idx_v));
    Eigen::Quaterniond r(moved.rotation);
    r.normalize();
    if (r.w() * quat.w() + r.vec().dot(quat.vec()) < 0) r.coeffs() *= -1;  // stay on q's hemisphere
    out.segment<3>(j.idx_q) = moved.translation;
    out.segment<4>(j.idx_q + 3) << r.x(), r.y(), r.z(), r.w();
  }
  return out;
}

// Uniform within the position limits; unbounded coordinates in [-pi, pi] (angles) or
// [-1, 1] (translations); a uniformly random unit quaternion for the free-flyer.
inline Eigen::VectorXd randomConfiguration(const Model& model, std::mt19937_64& rng) {
  auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
  };
  Eigen::VectorXd q(model.nq);
  for (const Joint& j : model.joints) {
    if (j.type == JointType::FreeFlyer) {
      for (int k = 0; k < 3; ++k) q[j.idx_q + k] = uniform(-1, 1);
      Eigen::Vector4d g;
      do {
        for (int k = 0; k < 4; ++k) g[k] = uniform(-1, 1);
      } while (g.norm() < 1e-3 || g.norm() > 1);
      q.segment<4>(j.idx_q + 3) = g.normalized();
      continue;
    }
    double lo = j.lower[0], hi = j.upper[0];
    double span = j.type == JointType::Revolute ? M_PI : 1.0;
    if (!std::isfinite(lo)) lo = -span;
    if (!std::isfinite(hi)) hi = span;
    q[j.idx_q] = uniform(lo, hi);
  }
  return q;
}

}  // namespace robodiff
