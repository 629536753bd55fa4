#include "robodiff/model/model.hpp"

#include <stdexcept>

namespace robodiff {

std::optional<int> Model::findJoint(const std::string& joint_name) const {
  for (int j = 0; j < njoints(); ++j)
    if (joints[j].name == joint_name) return j;
  return std::nullopt;
}

std::optional<int> Model::findFrame(const std::string& frame_name) const {
  for (int f = 0; f < nframes(); ++f)
    if (frames[f].name == frame_name) return f;
  return std::nullopt;
}

int Model::jointIndex(const std::string& joint_name) const {
  if (auto j = findJoint(joint_name)) return *j;
  throw std::invalid_argument("unknown joint '" + joint_name + "' in model '" + name + "'");
}

int Model::frameIndex(const std::string& frame_name) const {
  if (auto f = findFrame(frame_name)) return *f;
  throw std::invalid_argument("unknown frame '" + frame_name + "' in model '" + name + "'");
}

std::vector<std::string> Model::jointNames() const {
  std::vector<std::string> names;
  for (const Joint& j : joints) names.push_back(j.name);
  return names;
}

std::vector<std::string> Model::frameNames() const {
  std::vector<std::string> names;
  for (const Frame& f : frames) names.push_back(f.name);
  return names;
}

namespace {
Eigen::VectorXd stack(const Model& m, bool position, const Eigen::VectorXd Joint::*field) {
  Eigen::VectorXd out(position ? m.nq : m.nv);
  for (const Joint& j : m.joints) {
    if (position) out.segment(j.idx_q, j.nq) = j.*field;
    else out.segment(j.idx_v, j.nv) = j.*field;
  }
  return out;
}
}  // namespace

Eigen::VectorXd Model::lowerPositionLimit() const { return stack(*this, true, &Joint::lower); }
Eigen::VectorXd Model::upperPositionLimit() const { return stack(*this, true, &Joint::upper); }
Eigen::VectorXd Model::velocityLimit() const { return stack(*this, false, &Joint::velocity_limit); }
Eigen::VectorXd Model::effortLimit() const { return stack(*this, false, &Joint::effort_limit); }

void Model::finalize() {
  nq = nv = 0;
  for (int j = 0; j < njoints(); ++j) {
    Joint& joint = joints[j];
    if (joint.parent >= j) throw std::logic_error("joint '" + joint.name + "' comes before its parent");
    joint.idx_q = nq;
    joint.idx_v = nv;
    nq += joint.nq;
    nv += joint.nv;
  }
  subtree_end.assign(joints.size(), 0);
  for (int j = njoints() - 1; j >= 0; --j) {
    if (subtree_end[j] == 0) subtree_end[j] = j + 1;
    int p = joints[j].parent;
    if (p >= 0 && subtree_end[p] < subtree_end[j]) subtree_end[p] = subtree_end[j];
  }
}

const char* toString(JointType t) {
  switch (t) {
    case JointType::Revolute: return "revolute";
    case JointType::Prismatic: return "prismatic";
    case JointType::FreeFlyer: return "freeflyer";
  }
  return "?";
}

const char* toString(FrameType t) {
  switch (t) {
    case FrameType::Joint: return "JOINT";
    case FrameType::Body: return "BODY";
    case FrameType::FixedJoint: return "FIXED_JOINT";
  }
  return "?";
}

const char* toString(AxisKind k) {
  switch (k) {
    case AxisKind::X: return "x";
    case AxisKind::Y: return "y";
    case AxisKind::Z: return "z";
    case AxisKind::Unaligned: return "unaligned";
  }
  return "?";
}

}  // namespace robodiff
