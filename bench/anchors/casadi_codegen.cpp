// The CasADi side's source generation (casadi_codegen.hpp). Compiled with
// _GLIBCXX_USE_CXX11_ABI=0, the std::string ABI of the casadi wheel's libcasadi.
//
// Pinocchio's templated algorithm runs on its CasADi scalar (pinocchio/autodiff/casadi.hpp,
// each scalar a 1 x 1 casadi::SX) over symbolic inputs; the outputs, and for the Jacobian
// rows their SX Jacobian (densified), become a casadi::Function with common
// subexpressions eliminated ("cse"), and casadi::CodeGenerator writes its C.
#include <pinocchio/autodiff/casadi.hpp>  // first: Pinocchio's support of the SX scalar

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include <cstdio>
#include <string>

#include "casadi_codegen.hpp"

namespace anchors::casadi_codegen {
namespace {

using SX = casadi::SX;
using SXModel = pinocchio::ModelTpl<SX>;
using SXVector = Eigen::Matrix<SX, Eigen::Dynamic, 1>;

// The tree as a Pinocchio model on SX (joints added in order, as the parser added them).
SXModel sxModelOf(const Tree& tree) {
  SXModel m;
  for (std::size_t i = 1; i < tree.joints.size(); ++i) {
    const pinocchio::JointModel& joint = tree.joints[i];
    const SXVector zeros_v = SXVector::Constant(joint.nv(), SX(0)), zeros_q = SXVector::Constant(joint.nq(), SX(0));
    // Limits and friction are not read by RNEA or ABA: zeros keep numeric_limits<SX> out.
    m.addJoint(tree.parents[i], joint.cast<SX>(), tree.placements[i].cast<SX>(), "joint" + std::to_string(i), zeros_v,
               zeros_v, zeros_q, zeros_q, zeros_v, zeros_v);
  }
  for (std::size_t i = 0; i < tree.inertias.size(); ++i) m.inertias[i] = tree.inertias[i].cast<SX>();
  m.armature = tree.armature.cast<SX>();
  m.gravity = tree.gravity.cast<SX>();
  return m;
}

// An Eigen vector of the n scalars of a symbolic column `sym`.
SXVector entriesOf(const SX& sym) {
  SXVector v(sym.size1());
  for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = sym(static_cast<casadi_int>(i));
  return v;
}

// The step rows' outputs: [q_next; v_next] and, for step_cost, l at q.
SXVector stepOutputs(const Tree& tree, const SXModel& model, pinocchio::DataTpl<SX>& data, Algorithm algorithm,
                     const StepParameters& step, const SXVector& q, const SXVector& v, const SXVector& u) {
  const SX dt(step.dt);
  const SXVector v_next = v + dt * pinocchio::aba(model, data, q, v, u);
  const SXVector q_next = pinocchio::integrate(model, q, SXVector(dt * v_next));
  SXVector y(model.nq + model.nv + (algorithm == Algorithm::step_cost ? 1 : 0));
  y << q_next, v_next;
  if (algorithm != Algorithm::step_cost) return y;
  pinocchio::forwardKinematics(model, data, q);
  const auto frame = data.oMi[tree.frame_parent] * tree.frame_placement.cast<SX>();
  SX l = SX(step.control_weight) * u.dot(u);
  for (int k = 0; k < 3; ++k) {
    const SX e = frame.translation()[k] - SX(step.target[k]);
    l += e * e;
  }
  y[y.size() - 1] = l;
  return y;
}

casadi::Function buildFunction(const Tree& tree, Algorithm algorithm, const StepParameters& step, bool with_jacobian,
                               const std::string& name) {
  const SXModel model = sxModelOf(tree);
  pinocchio::DataTpl<SX> data(model);
  const SX q = SX::sym("q", model.nq), dq = SX::sym("dq", model.nv);
  const SX v = SX::sym("v", model.nv), u = SX::sym("u", model.nv);
  SXVector q_at = entriesOf(q);
  if (with_jacobian) q_at = pinocchio::integrate(model, q_at, entriesOf(dq));
  SXVector y_eigen;
  if (algorithm == Algorithm::rnea) y_eigen = pinocchio::rnea(model, data, q_at, entriesOf(v), entriesOf(u));
  else if (algorithm == Algorithm::aba) y_eigen = pinocchio::aba(model, data, q_at, entriesOf(v), entriesOf(u));
  else y_eigen = stepOutputs(tree, model, data, algorithm, step, q_at, entriesOf(v), entriesOf(u));
  SX y_sparse;
  pinocchio::casadi::copy(y_eigen, y_sparse);
  const SX y = SX::densify(y_sparse);  // every entry stored: the C function writes nv values
  const casadi::Dict options{{"cse", true}};
  if (!with_jacobian) return casadi::Function(name, casadi::SXVector{q, v, u}, casadi::SXVector{y}, options);
  const SX jacobian = SX::densify(SX::jacobian(y, SX::vertcat(casadi::SXVector{dq, v, u})));
  return casadi::Function(name, casadi::SXVector{q, dq, v, u}, casadi::SXVector{y, jacobian}, options);
}

}  // namespace

bool generateSource(const Tree& tree, Algorithm algorithm, const StepParameters& step, bool with_jacobian,
                    const char* name, const char* c_file, char* error, std::size_t error_size) {
  try {
    const casadi::Function function = buildFunction(tree, algorithm, step, with_jacobian, name);
    casadi::CodeGenerator generator(c_file, casadi::Dict{{"with_header", false}});
    generator.add(function);
    generator.generate();
    return true;
  } catch (const std::exception& e) {
    std::snprintf(error, error_size, "CasADi: %s", e.what());
    return false;
  }
}

void casadiVersion(char* out, std::size_t out_size) {
  std::snprintf(out, out_size, "%s", casadi::CasadiMeta::version());
}

}  // namespace anchors::casadi_codegen
