#include "mass_matrix_check.hpp"

#include <Eigen/Eigenvalues>

#include "robodiff/model/model_error.hpp"

namespace robodiff::detail {
namespace {

// Pivots below this share of the articulated inertia's size are rounding noise of zero.
constexpr double kRelativeTolerance = 1e-12;

// The motion transform taking twists from the parent joint frame to this joint's frame
// ([linear; angular]), from parentMjoint.
Mat6<double> childFromParent(const SE3<double>& parent_m_joint) {
  const Mat3<double> rt = parent_m_joint.rotation.transpose();
  Mat6<double> x = Mat6<double>::Zero();
  x.block<3, 3>(0, 0) = rt;
  x.block<3, 3>(0, 3) = -rt * skew<double>(parent_m_joint.translation);
  x.block<3, 3>(3, 3) = rt;
  return x;
}

Vec6<double> motionSubspace(const Joint& joint) {
  Vec6<double> s = Vec6<double>::Zero();
  if (joint.type == JointType::Prismatic) s.head<3>() = joint.axis;
  else s.tail<3>() = joint.axis;
  return s;
}

// "links 'a', 'b'": the URDF links that joint `j` moves.
std::string linksOf(const Model& model, int j) {
  std::string list;
  int shown = 0;
  for (const Frame& f : model.frames) {
    if (f.type != FrameType::Body || f.parent_joint != j) continue;
    if (++shown > 5) return list + ", ...";
    list += (list.empty() ? "'" : ", '") + f.name + "'";
  }
  return (shown == 1 ? "link " : "links ") + list;
}

[[noreturn]] void singular(const Model& model, const std::string& source, int j, const std::string& why) {
  throw PhysicallyInvalidModel(source + ": joint '" + model.joints[j].name + "' moves " + why + " (" +
                               linksOf(model, j) + " and everything beyond): the mass matrix is singular, so " +
                               "forward dynamics has no solution");
}

}  // namespace

// The articulated-body pivots of ABA at q = 0 are all positive exactly when the mass
// matrix at q = 0 is positive definite; one backward pass, no recursion.
void checkMassMatrixRegular(const Model& model, const std::string& source) {
  std::vector<Mat6<double>> articulated(model.joints.size());
  for (int j = 0; j < model.njoints(); ++j) articulated[j] = model.bodies[j].matrix();
  for (int j = model.njoints() - 1; j >= 0; --j) {
    const Joint& joint = model.joints[j];
    Mat6<double>& ia = articulated[j];
    const double size = ia.cwiseAbs().maxCoeff();
    Mat6<double> passed;
    if (joint.type == JointType::FreeFlyer) {
      Eigen::SelfAdjointEigenSolver<Mat6<double>> eig(ia, Eigen::EigenvaluesOnly);
      if (!(eig.eigenvalues().minCoeff() > kRelativeTolerance * size))
        singular(model, source, j, "a robot with no mass or a singular inertia");
      passed.setZero();
    } else {
      const Vec6<double> s = motionSubspace(joint);
      const Vec6<double> u = ia * s;
      const double d = s.dot(u);
      if (!(d > kRelativeTolerance * size))
        singular(model, source, j, "no mass or inertia in its direction of motion");
      passed = ia - u * u.transpose() / d;
    }
    if (joint.parent >= 0) {
      const Mat6<double> x = childFromParent(joint.placement);
      articulated[joint.parent] += x.transpose() * passed * x;
    }
  }
}

}  // namespace robodiff::detail
