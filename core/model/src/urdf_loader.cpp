#include "robodiff/model/urdf_loader.hpp"

#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <mutex>
#include <sstream>

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include "mass_matrix_check.hpp"
#include "portable_geometry.hpp"
#include "urdf_validation.hpp"
#include "utf8_check.hpp"
#include "xacro_check.hpp"

namespace robodiff {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double snap(double x) {
  if (std::abs(x) <= kRotationSnapTolerance) return 0.0;
  if (std::abs(x - 1.0) <= kRotationSnapTolerance) return 1.0;
  if (std::abs(x + 1.0) <= kRotationSnapTolerance) return -1.0;
  return x;
}

// The rpy angles the validator read for `name`; every joint and every link with an
// <inertial> has an entry.
const std::array<double, 3>& rpyOf(const std::map<std::string, std::array<double, 3>>& angles,
                                   const std::string& name) {
  auto it = angles.find(name);
  if (it == angles.end()) throw std::logic_error("URDF loader: no origin angles recorded for '" + name + "'");
  return it->second;
}

// An origin: the translation urdfdom parsed (exactly) and the rotation of the rpy as
// written, computed portably (urdfdom's quaternion depends on the host's libm).
SE3<double> toSE3(const urdf::Pose& pose, const std::array<double, 3>& rpy) {
  return {portable::rpyRotation(rpy[0], rpy[1], rpy[2]).unaryExpr(&snap),
          Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z)};
}

// Inertia of a URDF link, in the link frame.
Inertia<double> linkInertia(const urdf::Link& link, const detail::UrdfRotations& rotations) {
  if (!link.inertial) return Inertia<double>::Zero();
  const urdf::Inertial& in = *link.inertial;
  SE3<double> origin = toSE3(in.origin, rpyOf(rotations.inertial_rpy, link.name));
  Eigen::Matrix3d I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  return Inertia<double>{in.mass, origin.translation, portable::rotateInertia(origin.rotation, I)};
}

void setAxis(Joint& joint, const urdf::Vector3& axis) {
  Eigen::Vector3d a(axis.x, axis.y, axis.z);
  a = portable::normalized(a).unaryExpr(&snap);
  joint.axis = a;
  joint.axis_kind = a == Eigen::Vector3d::UnitX()   ? AxisKind::X
                    : a == Eigen::Vector3d::UnitY() ? AxisKind::Y
                    : a == Eigen::Vector3d::UnitZ() ? AxisKind::Z
                                                    : AxisKind::Unaligned;
}

Joint makeJoint(const urdf::Joint& uj, int parent, const SE3<double>& placement) {
  Joint j;
  j.name = uj.name;
  j.parent = parent;
  j.placement = placement;
  j.type = uj.type == urdf::Joint::PRISMATIC ? JointType::Prismatic : JointType::Revolute;
  j.continuous = uj.type == urdf::Joint::CONTINUOUS;
  j.nq = j.nv = 1;
  setAxis(j, uj.axis);
  double lower = -kInf, upper = kInf, velocity = kInf, effort = kInf;
  if (uj.limits) {
    if (!j.continuous) lower = uj.limits->lower, upper = uj.limits->upper;
    if (uj.limits->velocity > 0) velocity = uj.limits->velocity;
    if (uj.limits->effort > 0) effort = uj.limits->effort;
  }
  j.lower = Eigen::VectorXd::Constant(1, lower);
  j.upper = Eigen::VectorXd::Constant(1, upper);
  j.velocity_limit = Eigen::VectorXd::Constant(1, velocity);
  j.effort_limit = Eigen::VectorXd::Constant(1, effort);
  j.damping = Eigen::VectorXd::Constant(1, uj.dynamics ? uj.dynamics->damping : 0.0);
  j.friction = Eigen::VectorXd::Constant(1, uj.dynamics ? uj.dynamics->friction : 0.0);
  return j;
}

Joint makeFreeFlyer() {
  Joint j;
  j.name = "root_joint";
  j.type = JointType::FreeFlyer;
  j.parent = -1;
  j.nq = 7;
  j.nv = 6;
  j.lower = Eigen::VectorXd::Constant(7, -kInf);
  j.upper = Eigen::VectorXd::Constant(7, kInf);
  j.velocity_limit = Eigen::VectorXd::Constant(6, kInf);
  j.effort_limit = Eigen::VectorXd::Constant(6, kInf);
  j.damping = j.friction = Eigen::VectorXd::Zero(6);
  return j;
}

// urdfdom reports through console_bridge; collect its errors for our message.
class CollectErrors : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) messages += (messages.empty() ? "" : "; ") + text;
  }
  std::string messages;
};

urdf::ModelInterfaceSharedPtr parseWithUrdfdom(const std::string& xml, const std::string& source) {
  static std::mutex mutex;  // console_bridge's handler is process-global
  std::lock_guard<std::mutex> lock(mutex);
  CollectErrors errors;
  console_bridge::useOutputHandler(&errors);
  urdf::ModelInterfaceSharedPtr parsed = urdf::parseURDF(xml);
  console_bridge::restorePreviousOutputHandler();
  if (!parsed)
    throw ModelError(source + ": urdfdom rejected the URDF: " +
                     (errors.messages.empty() ? "no reason given" : errors.messages));
  return parsed;
}

// A URDF joint still to be visited, with where its origin sits in the model: the
// moving joint above it and the placement of the origin in that joint's frame.
struct Pending {
  urdf::JointConstSharedPtr joint;  // null for the root link
  urdf::LinkConstSharedPtr child;
  int parent;
  SE3<double> placement;
};

Model build(const urdf::ModelInterface& urdf_model, RootJoint root, const detail::UrdfRotations& rotations) {
  Model model;
  model.name = urdf_model.getName();
  model.root = root;
  model.frames.push_back({"universe", FrameType::FixedJoint, -1, SE3<double>::Identity()});

  int root_joint = -1;
  if (root == RootJoint::FreeFlyer) {
    model.joints.push_back(makeFreeFlyer());
    model.bodies.push_back(Inertia<double>::Zero());
    model.frames.push_back({"root_joint", FrameType::Joint, 0, SE3<double>::Identity()});
    root_joint = 0;
  }

  // Depth-first pre-order, children in urdfdom's order; an explicit stack, so that
  // deep chains need no deep recursion.
  std::vector<Pending> stack{{nullptr, urdf_model.getRoot(), root_joint, SE3<double>::Identity()}};
  while (!stack.empty()) {
    Pending at = stack.back();
    stack.pop_back();
    int joint = at.parent;
    SE3<double> link_placement = at.placement;
    if (at.joint && at.joint->type == urdf::Joint::FIXED) {
      model.frames.push_back({at.joint->name, FrameType::FixedJoint, joint, link_placement});
    } else if (at.joint) {
      joint = model.njoints();
      model.joints.push_back(makeJoint(*at.joint, at.parent, at.placement));
      model.bodies.push_back(Inertia<double>::Zero());
      model.frames.push_back({at.joint->name, FrameType::Joint, joint, SE3<double>::Identity()});
      link_placement = SE3<double>::Identity();
    }
    const urdf::Link& link = *at.child;
    if (joint >= 0)  // bodies fixed to the universe do not move and carry no dynamics
      model.bodies[joint] = portable::mergeInertias(
          model.bodies[joint], portable::transformInertia(linkInertia(link, rotations), link_placement));
    model.frames.push_back({link.name, FrameType::Body, joint, link_placement});

    const auto& children = link.child_joints;
    for (auto it = children.rbegin(); it != children.rend(); ++it)
      stack.push_back({*it, urdf_model.getLink((*it)->child_link_name), joint,
                       portable::compose(link_placement, toSE3((*it)->parent_to_joint_origin_transform,
                                                               rpyOf(rotations.joint_rpy, (*it)->name)))});
  }
  model.finalize();
  return model;
}

// XML turns a tab or line break inside an attribute value into a space (attribute-value
// normalisation, XML 1.0 section 3.3.3), but TinyXML does not and urdfdom splits vectors
// such as xyz="0 0 1" on spaces only. Outside attribute values these characters are
// whitespace or text that urdfdom ignores, so they are replaced everywhere; the
// validator has already seen the original text, with its line numbers.
std::string normaliseWhitespace(std::string xml) {
  for (char& c : xml)
    if (c == '\t' || c == '\n' || c == '\r') c = ' ';
  return xml;
}

}  // namespace

Model loadUrdfString(const std::string& xml, RootJoint root, const std::string& source_name,
                     const UrdfLimits& limits, PhysicsCheck physics) {
  checkUrdfLimits(xml, limits, source_name);  // before the parsers, which recurse per level
  detail::checkUtf8(xml, source_name);         // before TinyXML, which reads past a cut sequence
  detail::refuseXacro(xml, source_name);       // a clear word instead of "no <link>"
  const bool dynamic = physics == PhysicsCheck::Dynamic;
  const detail::UrdfRotations rotations = detail::validateUrdfXml(xml, source_name, dynamic);
  urdf::ModelInterfaceSharedPtr parsed = parseWithUrdfdom(normaliseWhitespace(xml), source_name);
  Model model = build(*parsed, root, rotations);
  if (dynamic) detail::checkMassMatrixRegular(model, source_name);
  return model;
}

Model loadUrdfFile(const std::string& path, RootJoint root, const UrdfLimits& limits, PhysicsCheck physics) {
  std::error_code ec;  // a directory opens as a stream and reads as an empty document
  if (std::filesystem::is_directory(path, ec))
    throw ModelError(path + ": cannot read URDF file: it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelError(path + ": cannot open URDF file: " + std::strerror(errno));
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > limits.max_bytes)  // refused before reading it
    throw ModelTooLarge(path + ": the URDF is " + std::to_string(size) + " bytes; the limit is max_bytes = " +
                            std::to_string(limits.max_bytes),
                        "max_bytes", size, limits.max_bytes);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ModelError(path + ": cannot read URDF file");
  return loadUrdfString(text.str(), root, path, limits, physics);
}

}  // namespace robodiff
