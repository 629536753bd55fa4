// Forward kinematics: placements of every joint (and frame) in the world, and the
// spatial velocities / accelerations of the joints in their own frames.
#pragma once

#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/joint.hpp"

namespace robodiff {

// data.liMi, data.oMi for configuration q.
template <class S, class Q> void forwardKinematics(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  for (int j = 0; j < model.njoints(); ++j) {
    const Joint& joint = model.joints[j];
    data.liMi[j] = jointPlacement<S>(joint, q);
    data.oMi[j] = joint.parent >= 0 ? data.oMi[joint.parent] * data.liMi[j] : data.liMi[j];
  }
}

// ... plus data.v (joint velocities in joint frames) for velocity v.
template <class S, class Q, class V>
void forwardKinematics(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q, const Eigen::MatrixBase<V>& v) {
  for (int j = 0; j < model.njoints(); ++j) {
    const Joint& joint = model.joints[j];
    data.liMi[j] = jointPlacement<S>(joint, q);
    Motion<S> vj = jointMotion<S>(joint, v);
    if (joint.parent >= 0) {
      data.oMi[j] = data.oMi[joint.parent] * data.liMi[j];
      data.v[j] = data.liMi[j].actInv(data.v[joint.parent]) + vj;
    } else {
      data.oMi[j] = data.liMi[j];
      data.v[j] = vj;
    }
  }
}

namespace detail {

// The second-order forward pass: placements, velocities and accelerations, with a0 the
// acceleration of the universe (zero for kinematics; -gravity for dynamics).
template <class S, class Q, class V, class A>
void accelerationPass(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q, const Eigen::MatrixBase<V>& v,
                      const Eigen::MatrixBase<A>& a, const Motion<S>& a0) {
  for (int j = 0; j < model.njoints(); ++j) {
    const Joint& joint = model.joints[j];
    const int p = joint.parent;
    data.liMi[j] = jointPlacement<S>(joint, q);
    Motion<S> vj = jointMotion<S>(joint, v);
    Motion<S> aj = jointMotion<S>(joint, a);
    if (p >= 0) {
      data.oMi[j] = data.oMi[p] * data.liMi[j];
      data.v[j] = data.liMi[j].actInv(data.v[p]) + vj;
      data.a[j] = data.liMi[j].actInv(data.a[p]) + aj + data.v[j].cross(vj);
    } else {
      data.oMi[j] = data.liMi[j];
      data.v[j] = vj;
      data.a[j] = data.liMi[j].actInv(a0) + aj;
    }
  }
}

}  // namespace detail

// ... plus data.a (joint accelerations, gravity not included) for acceleration a.
template <class S, class Q, class V, class A>
void forwardKinematics(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q, const Eigen::MatrixBase<V>& v,
                       const Eigen::MatrixBase<A>& a) {
  detail::accelerationPass(model, data, q, v, a, Motion<S>::Zero());
}

// data.oMf from data.oMi (call after forwardKinematics).
template <class S> void updateFramePlacements(const Model& model, Data<S>& data) {
  for (int f = 0; f < model.nframes(); ++f) {
    const Frame& frame = model.frames[f];
    const auto& placement = asScalar<S>(frame.placement);
    data.oMf[f] = frame.parent_joint >= 0 ? data.oMi[frame.parent_joint] * placement : SE3<S>(placement);
  }
}

// Placement of one frame in the world (after forwardKinematics).
template <class S> SE3<S> framePlacement(const Model& model, const Data<S>& data, int frame_index) {
  const Frame& frame = model.frames[frame_index];
  const auto& placement = asScalar<S>(frame.placement);
  return frame.parent_joint >= 0 ? data.oMi[frame.parent_joint] * placement : SE3<S>(placement);
}

// The origin of one frame in the world for configuration q, from its own chain of joint
// placements alone: u = t_f, then u = liMi_j u from the frame's joint to the root. Each
// joint turns one vector (4 operations about a coordinate axis) where the world
// placements would multiply rotations; for the position alone no oMi is needed.
template <class S, class Q> Vec3<S> framePosition(const Model& model, const Eigen::MatrixBase<Q>& q, int frame_index) {
  const Frame& frame = model.frames[frame_index];
  Vec3<S> u = asScalar<S>(frame.placement).translation;
  for (int j = frame.parent_joint; j >= 0; j = model.joints[j].parent) u = jointPlacement<S>(model.joints[j], q).act(u);
  return u;
}

}  // namespace robodiff
