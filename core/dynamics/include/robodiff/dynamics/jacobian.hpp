// Frame Jacobians: J such that the frame's spatial velocity is J * v.
//
// Reference frames (as in Pinocchio):
//  - LOCAL: the velocity of the frame, expressed in the frame itself.
//  - WORLD: the spatial velocity expressed in the world frame at the world origin.
//  - LOCAL_WORLD_ALIGNED: the velocity of the frame's origin, with world-aligned axes.
// Rows are [linear x y z; angular x y z]; columns follow v.
#pragma once

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "robodiff/dynamics/kinematics.hpp"

namespace robodiff {

enum class ReferenceFrame { Local, World, LocalWorldAligned };

inline const char* toString(ReferenceFrame r) {
  switch (r) {
    case ReferenceFrame::Local: return "LOCAL";
    case ReferenceFrame::World: return "WORLD";
    case ReferenceFrame::LocalWorldAligned: return "LOCAL_WORLD_ALIGNED";
  }
  return "?";
}

inline ReferenceFrame parseReferenceFrame(const std::string& name) {
  if (name == "LOCAL") return ReferenceFrame::Local;
  if (name == "WORLD") return ReferenceFrame::World;
  if (name == "LOCAL_WORLD_ALIGNED") return ReferenceFrame::LocalWorldAligned;
  throw std::invalid_argument("unknown reference frame '" + name + "' (expected LOCAL, WORLD or LOCAL_WORLD_ALIGNED)");
}

// data.J: every joint's motion-subspace columns in the world frame, for configuration q.
template <class S, class Q>
const Matrix6X<S>& computeJointJacobians(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  forwardKinematics(model, data, q);
  for (int j = 0; j < model.njoints(); ++j) {
    const Joint& joint = model.joints[j];
    for (int k = 0; k < joint.nv; ++k) data.J.col(joint.idx_v + k) = worldSubspaceColumn(joint, data.oMi[j], k);
  }
  return data.J;
}

namespace detail {

// The joints from the root to `joint`, root first.
inline std::vector<int> pathFromRoot(const Model& model, int joint) {
  std::vector<int> path;
  for (int j = joint; j >= 0; j = model.joints[j].parent) path.push_back(j);
  return {path.rbegin(), path.rend()};
}

// For each joint of `path`, the world rotation to multiply the column's vector by:
// R_j w = R_a (Q_{a+1} ... Q_j w), with Q the joints' own rotations. Each revolute joint
// adds one level of products after its sin and cos, to R_j from the root side and to
// the offset u_j from the frame's side; the column waits for the deeper of R_a and the
// rotated vector. The a that ends soonest, the latest of those on ties (fewest products).
inline std::vector<int> balancedRotationJoints(const Model& model, const std::vector<int>& path) {
  const int m = static_cast<int>(path.size());
  std::vector<int> level(m + 1, 0);  // level[i + 1]: revolute joints in path[0..i]
  for (int i = 0; i < m; ++i) level[i + 1] = level[i] + (model.joints[path[i]].type == JointType::Revolute);
  std::vector<int> chosen(m);
  for (int i = 0; i < m; ++i) {
    const int offset_level = level[m] - level[i + 1];
    int best = i, best_depth = std::max(level[i + 1], offset_level);
    for (int a = i - 1; a >= 0; --a) {
      const int depth = std::max(level[a + 1], offset_level + level[i + 1] - level[a + 1]);
      if (depth < best_depth) best = a, best_depth = depth;
    }
    chosen[i] = best;
  }
  return chosen;
}

// LOCAL_WORLD_ALIGNED from the placements alone: column (joint j, k) is
// R_j [s_lin + s_ang x u_j; s_ang], with R_j joint j's world rotation, s its subspace
// column in its own frame and u_j = p_f - p_j in joint j's frame. The offsets u_j are
// summed from the frame towards the root in the joints' own frames (u_parent =
// liMi u_j + t_j), so they wait only on each joint's own sin and cos, not on the chain
// of world rotations, and no world position enters: nothing cancels where the robot
// stands far from the origin. The linear part is rotated to the world in two steps
// where that ends sooner (balancedRotationJoints): a frame Jacobian is a chain of
// latencies, not of throughput.
template <class S> Matrix6X<S> frameJacobianWorldAligned(const Model& model, const Data<S>& data, int frame_index) {
  Matrix6X<S> J = Matrix6X<S>::Zero(6, model.nv);
  const Frame& frame = model.frames[frame_index];
  if (frame.parent_joint < 0) return J;
  const std::vector<int> path = pathFromRoot(model, frame.parent_joint);
  const std::vector<int> rotate_by = balancedRotationJoints(model, path);
  Vec3<S> to_frame = asScalar<S>(frame.placement).translation;  // u_j
  for (int i = static_cast<int>(path.size()) - 1; i >= 0; --i) {
    const int j = path[i];
    const Joint& joint = model.joints[j];
    const Mat3<S>& R = data.oMi[j].rotation;
    for (int k = 0; k < joint.nv; ++k) {
      const Motion<S> s = subspaceColumn<S>(joint, k);
      J.template block<3, 1>(3, joint.idx_v + k) = rotatedSubspaceColumn(joint, R, k).angular;
      Vec3<S> w = s.linear + s.angular.cross(to_frame);
      for (int t = i; t > rotate_by[i]; --t) w = data.liMi[path[t]].rotation * w;
      J.template block<3, 1>(0, joint.idx_v + k) = data.oMi[path[rotate_by[i]]].rotation * w;
    }
    if (joint.parent >= 0) to_frame = data.liMi[j].act(to_frame);
  }
  return J;
}

}  // namespace detail

// The 6 x nv Jacobian of a frame (after computeJointJacobians, or after
// forwardKinematics when `data.J` is filled).
template <class S>
Matrix6X<S> frameJacobian(const Model& model, const Data<S>& data, int frame_index, ReferenceFrame reference) {
  if (reference == ReferenceFrame::LocalWorldAligned) return detail::frameJacobianWorldAligned(model, data, frame_index);
  Matrix6X<S> J = Matrix6X<S>::Zero(6, model.nv);
  const Frame& frame = model.frames[frame_index];
  for (int j = frame.parent_joint; j >= 0; j = model.joints[j].parent) {
    const Joint& joint = model.joints[j];
    J.middleCols(joint.idx_v, joint.nv) = data.J.middleCols(joint.idx_v, joint.nv);
  }
  if (reference == ReferenceFrame::World) return J;
  return framePlacement(model, data, frame_index).actInvMotions(J);  // LOCAL
}

// Convenience: kinematics and one frame Jacobian at q (and data.J, the joint Jacobians,
// except for LOCAL_WORLD_ALIGNED, which needs only the placements).
template <class S, class Q>
Matrix6X<S> computeFrameJacobian(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q, int frame_index,
                                 ReferenceFrame reference) {
  if (reference == ReferenceFrame::LocalWorldAligned) forwardKinematics(model, data, q);
  else computeJointJacobians(model, data, q);
  return frameJacobian(model, data, frame_index, reference);
}

}  // namespace robodiff
