// Workspace of the dynamics algorithms for one model and one scalar type. Everything is
// sized at construction, so the algorithms never allocate (for double).
#pragma once

#include <vector>

#include "robodiff/model/model.hpp"
#include "robodiff/spatial/force.hpp"
#include "robodiff/spatial/inertia.hpp"
#include "robodiff/spatial/motion.hpp"
#include "robodiff/spatial/se3.hpp"

namespace robodiff {

// A joint's 6 x nv block (motion subspace, U of ABA); at most 6 columns, no heap.
template <class S> using JointBlock = Eigen::Matrix<S, 6, Eigen::Dynamic, 0, 6, 6>;
template <class S> using JointSquare = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
template <class S> using JointVector = Eigen::Matrix<S, Eigen::Dynamic, 1, 0, 6, 1>;

// Inertia in its linear parametrisation [m 1, -h^; h^, I_o] (h = m c, I_o about the
// frame origin): sums of bodies in one frame are plain sums of these.
template <class S> struct InertiaSum {
  S mass = S(0);
  Vec3<S> h = Vec3<S>::Zero();
  Mat3<S> rotational = Mat3<S>::Zero();

  InertiaSum& operator+=(const InertiaSum& o) {
    mass += o.mass;
    h += o.h;
    rotational += o.rotational;
    return *this;
  }
  Force<S> operator*(const Motion<S>& v) const {
    return {mass * v.linear - h.cross(v.angular), h.cross(v.linear) + rotational * v.angular};
  }

  // A body's inertia in this form (constants when S is symbolic).
  static InertiaSum of(const Inertia<double>& body) {
    InertiaSum y;
    y.mass = S(body.mass);
    y.h = (body.mass * body.lever).template cast<S>();
    y.rotational = body.inertiaAboutOrigin().template cast<S>();
    return y;
  }

  // This inertia (given in frame b) expressed in frame a, with aMb = (R, p). With
  // h_r = R h: h' = h_r + m p and, about the new origin,
  // I' = R I R^T + (2 p.h_r + m |p|^2) 1 - (h_r p^T + p h_r^T + m p p^T).
  InertiaSum transformedBy(const SE3<S>& aMb) const {
    const Mat3<S>& R = aMb.rotation;
    const Vec3<S>& p = aMb.translation;
    InertiaSum out;
    out.mass = mass;
    const Vec3<S> hr = R * h;
    out.h = hr + mass * p;
    const Mat3<S> RI = R * rotational;
    const S trace_term = S(2) * p.dot(hr) + mass * p.squaredNorm();
    for (int r = 0; r < 3; ++r)
      for (int k = r; k < 3; ++k) {
        S value = RI.row(r).dot(R.row(k)) - (hr[r] * p[k] + p[r] * hr[k] + mass * (p[r] * p[k]));
        if (r == k) value += trace_term;
        out.rotational(r, k) = value;
        out.rotational(k, r) = value;
      }
    return out;
  }

  // This inertia turned about coordinate axis k by the angle whose cosine and sine are c
  // and s (a revolute joint about that axis). The plane block [A D; D B] of the rotational
  // inertia becomes [A c^2 + B s^2 - 2 D cs, (A - B) cs + D (c^2 - s^2); ...,
  // A s^2 + B c^2 + 2 D cs]: the products of c and s depend on the angle alone, so each
  // entry waits on the inertia for one multiply-add chain.
  InertiaSum rotatedAboutAxis(int k, const S& c, const S& s) const {
    const int i = (k + 1) % 3, l = (k + 2) % 3;
    const S cc = c * c, ss = s * s, cs = c * s;
    const S cs2 = cs + cs, cos2 = cc - ss;
    const Mat3<S>& I = rotational;
    InertiaSum out;
    out.mass = mass;
    out.h[k] = h[k];
    out.h[i] = c * h[i] - s * h[l];
    out.h[l] = s * h[i] + c * h[l];
    Mat3<S>& O = out.rotational;
    O(i, i) = I(i, i) * cc + I(l, l) * ss - I(i, l) * cs2;
    O(l, l) = I(i, i) * ss + I(l, l) * cc + I(i, l) * cs2;
    O(i, l) = O(l, i) = (I(i, i) - I(l, l)) * cs + I(i, l) * cos2;
    O(i, k) = O(k, i) = c * I(i, k) - s * I(l, k);
    O(l, k) = O(k, l) = s * I(i, k) + c * I(l, k);
    O(k, k) = I(k, k);
    return out;
  }
};

template <class S> struct Data {
  explicit Data(const Model& model)
      : liMi(model.njoints()), oMi(model.njoints()), oMf(model.nframes()),
        v(model.njoints()), a(model.njoints()), c(model.njoints()), f(model.njoints()),
        tau(VecX<S>::Zero(model.nv)), ddq(VecX<S>::Zero(model.nv)),
        M(MatX<S>::Zero(model.nv, model.nv)), J(Matrix6X<S>::Zero(6, model.nv)), Ag(Matrix6X<S>::Zero(6, model.nv)),
        Ycrb(model.njoints()), Ia(model.njoints()), pA(model.njoints()),
        U(model.njoints()), D(model.njoints()), Dinv(model.njoints()), u(model.njoints()) {
    for (int j = 0; j < model.njoints(); ++j) {
      int nv = model.joints[j].nv;
      U[j].resize(6, nv);
      D[j].resize(nv, nv);
      Dinv[j].resize(nv, nv);
      u[j].resize(nv);
    }
  }

  // Kinematics, per joint: placement in the parent joint frame and in the world; spatial
  // velocity, acceleration and bias acceleration in the joint frame.
  std::vector<SE3<S>> liMi, oMi;
  std::vector<SE3<S>> oMf;  // placement of every frame in the world
  std::vector<Motion<S>> v, a, c;
  std::vector<Force<S>> f;  // RNEA: force transmitted by each joint, in its frame

  VecX<S> tau;     // RNEA output
  VecX<S> ddq;     // ABA output
  MatX<S> M;       // CRBA output (full, symmetric)
  Matrix6X<S> J;   // joint Jacobian columns in the world frame (crba, computeJointJacobians)
  Matrix6X<S> Ag;  // CRBA: composite inertia times J, per column

  std::vector<InertiaSum<S>> Ycrb;   // CRBA: composite inertias, each in its joint's frame
  std::vector<Mat6<S>> Ia;           // ABA: articulated inertias
  std::vector<Force<S>> pA;          // ABA: bias forces
  std::vector<JointBlock<S>> U;
  std::vector<JointSquare<S>> D;     // ABA: S^T Ia S, the joint-space articulated inertia
  std::vector<JointSquare<S>> Dinv;  // its inverse (but for a multi-DoF root, which is solved with D)
  std::vector<JointVector<S>> u;

  Vec3<S> com = Vec3<S>::Zero();
  S mass = S(0);
};

}  // namespace robodiff
