// The kinematic tree of a robot: joints in model order, the composite body carried by
// each joint, and named frames. Constant after loading; algorithms keep their
// workspace in a separate Data (core/dynamics), as in Pinocchio.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/spatial/inertia.hpp"
#include "robodiff/spatial/se3.hpp"

namespace robodiff {

enum class JointType {
  Revolute,   // URDF revolute and continuous: q = angle (nq = nv = 1)
  Prismatic,  // q = displacement along the axis
  FreeFlyer,  // root only: q = [x y z qx qy qz qw], v = [linear; angular] in the base frame
};

// Which coordinate axis a revolute/prismatic joint moves along (Unaligned: any other
// unit axis, negative ones included). Lets algorithms pick a cheaper joint transform.
enum class AxisKind { X, Y, Z, Unaligned };

enum class FrameType {
  Joint,       // the frame of a moving joint
  Body,        // the frame of a URDF link
  FixedJoint,  // the frame of a URDF fixed joint (its child link's origin)
};

enum class RootJoint { Fixed, FreeFlyer };

struct Joint {
  std::string name;
  JointType type = JointType::Revolute;
  AxisKind axis_kind = AxisKind::Unaligned;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit axis in the joint frame
  int parent = -1;                                  // parent joint index, -1: the universe
  SE3<double> placement;                            // parent joint frame -> this joint frame at q = 0
  int idx_q = 0, nq = 1, idx_v = 0, nv = 1;
  bool continuous = false;                          // URDF continuous: no position limits
  // Limits, sized nq (position) and nv (velocity, effort); +-inf where the URDF gives none.
  Eigen::VectorXd lower, upper, velocity_limit, effort_limit;
  Eigen::VectorXd damping, friction;                // URDF <dynamics>, sized nv
};

struct Frame {
  std::string name;
  FrameType type = FrameType::Body;
  int parent_joint = -1;   // -1: attached to the universe
  SE3<double> placement;   // in the parent joint's frame
};

class Model {
 public:
  std::string name;                    // the URDF robot name (not part of the canonical form)
  RootJoint root = RootJoint::Fixed;
  std::vector<Joint> joints;           // depth-first: every parent before its children
  std::vector<Inertia<double>> bodies; // composite body moved by each joint, in its frame
  std::vector<Frame> frames;           // every URDF link and joint, plus "universe"
  std::vector<int> subtree_end;        // joints [j, subtree_end[j]) are j and its descendants
  int nq = 0, nv = 0;
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};

  int njoints() const { return static_cast<int>(joints.size()); }
  int nframes() const { return static_cast<int>(frames.size()); }

  // Index of the joint / frame with that name; nullopt when there is none.
  std::optional<int> findJoint(const std::string& joint_name) const;
  std::optional<int> findFrame(const std::string& frame_name) const;
  // As above, but throw std::invalid_argument naming the unknown name.
  int jointIndex(const std::string& joint_name) const;
  int frameIndex(const std::string& frame_name) const;

  // True when joint `ancestor` is `joint` or lies on its path to the root.
  bool supports(int ancestor, int joint) const {
    return ancestor <= joint && joint < subtree_end[ancestor];
  }

  std::vector<std::string> jointNames() const;
  std::vector<std::string> frameNames() const;

  // Position and velocity limits stacked over the joints (sizes nq and nv). The
  // free-flyer's translation and quaternion are unbounded.
  Eigen::VectorXd lowerPositionLimit() const;
  Eigen::VectorXd upperPositionLimit() const;
  Eigen::VectorXd velocityLimit() const;
  Eigen::VectorXd effortLimit() const;

  // Recompute idx_q/idx_v, nq/nv and subtree_end from joints (after editing them).
  void finalize();
};

const char* toString(JointType t);
const char* toString(FrameType t);
const char* toString(AxisKind k);

}  // namespace robodiff
