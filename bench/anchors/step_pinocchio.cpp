// The Pinocchio side of the step rows (step_rows.hpp): ABA and its analytic derivatives,
// dIntegrate and the frame's Jacobian, composed by hand on one preallocated Data, timed
// like `robodiff bench`. Its outputs at the check states are the reference the other
// sides' steps are checked against.
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>

#include "step_rows.hpp"

namespace anchors {

const std::vector<std::string> kStepRows = {"euler_step_value", "euler_step_jacobian", "step_cost_value",
                                            "step_cost_derivatives"};

namespace {

using robodiff::cli::bench::doNotOptimize;

constexpr double kHessianStep = 1e-5;  // central differences of the analytic gradient (a check only)

struct PinocchioStepRunner {
  const pinocchio::Model& model;
  const pinocchio::FrameIndex frame;
  const Eigen::Vector3d target;
  pinocchio::Data data;
  Eigen::VectorXd v_next, dq, q_next, e;
  Eigen::MatrixXd da_dq, da_dv, Jq, Jv, J;  // J: the step's Jacobian, 2nv x 3nv
  pinocchio::Data::Matrix6x frame_j;
  Eigen::VectorXd gradient;  // of l w.r.t. [q, v, u]
  Eigen::MatrixXd hessian;   // Gauss-Newton
  double l = 0;

  explicit PinocchioStepRunner(const pinocchio::Model& m)
      : model(m), frame(lastFrame(m)), target(kCostTarget[0], kCostTarget[1], kCostTarget[2]), data(m),
        v_next(m.nv), dq(m.nv), q_next(m.nq), e(3), da_dq(Eigen::MatrixXd::Zero(m.nv, m.nv)), da_dv(da_dq),
        Jq(da_dq), Jv(da_dq), J(Eigen::MatrixXd::Zero(2 * m.nv, 3 * m.nv)),
        frame_j(pinocchio::Data::Matrix6x::Zero(6, m.nv)), gradient(Eigen::VectorXd::Zero(3 * m.nv)),
        hessian(Eigen::MatrixXd::Zero(3 * m.nv, 3 * m.nv)) {}

  // v_next, q_next from data.ddq.
  void integrateStep(const State& s) {
    v_next = s.v + kStepDt * data.ddq;
    dq = kStepDt * v_next;
    pinocchio::integrate(model, s.q, dq, q_next);
  }

  // l from the frame's placement (the joints' placements are in data).
  void cost(const State& s) {
    pinocchio::updateFramePlacement(model, data, frame);
    e = data.oMf[frame].translation() - target;
    l = e.squaredNorm() + kControlWeight * s.tau.squaredNorm();
  }

  void value(const State& s, bool with_cost) {
    pinocchio::aba(model, data, s.q, s.v, s.tau);
    integrateStep(s);
    if (with_cost) {
      pinocchio::updateGlobalPlacements(model, data);
      cost(s);
    }
  }

  // The step's Jacobian: dv_next = [dt da/dq, I + dt da/dv, dt Minv]; dq_next =
  // dIntegrate/dq + dIntegrate/dv dt dv_next (for the q columns), dIntegrate/dv dt dv_next.
  void derivatives(const State& s, bool with_cost) {
    const int nv = model.nv;
    pinocchio::computeABADerivatives(model, data, s.q, s.v, s.tau, da_dq, da_dv, data.Minv);
    data.Minv.triangularView<Eigen::StrictlyLower>() = data.Minv.transpose().triangularView<Eigen::StrictlyLower>();
    integrateStep(s);
    auto dv_next = J.bottomRows(nv);
    dv_next.leftCols(nv) = kStepDt * da_dq;
    dv_next.middleCols(nv, nv) = kStepDt * da_dv;
    dv_next.middleCols(nv, nv).diagonal().array() += 1.0;
    dv_next.rightCols(nv) = kStepDt * data.Minv;
    pinocchio::dIntegrate(model, s.q, dq, Jq, pinocchio::ARG0);
    pinocchio::dIntegrate(model, s.q, dq, Jv, pinocchio::ARG1);
    J.topRows(nv).noalias() = (kStepDt * Jv) * dv_next;
    J.topLeftCorner(nv, nv) += Jq;
    if (!with_cost) return;
    cost(s);  // computeABADerivatives left the joints' placements and Jacobians in data
    pinocchio::getFrameJacobian(model, data, frame, pinocchio::LOCAL_WORLD_ALIGNED, frame_j);
    const auto Jp = frame_j.topRows<3>();
    gradient.head(nv).noalias() = 2.0 * Jp.transpose() * e;
    gradient.tail(nv) = 2.0 * kControlWeight * s.tau;
    hessian.topLeftCorner(nv, nv).noalias() = 2.0 * Jp.transpose() * Jp;
    hessian.bottomRightCorner(nv, nv).diagonal().setConstant(2.0 * kControlWeight);
  }

  void call(const std::string& row, const State& s) {
    if (row == "euler_step_value") value(s, false);
    else if (row == "step_cost_value") value(s, true);
    else if (row == "euler_step_jacobian") derivatives(s, false);
    else if (row == "step_cost_derivatives") derivatives(s, true);
    doNotOptimize(data);
    doNotOptimize(J);
  }

  // The exact Hessian of l: central differences of the analytic gradient along each
  // tangent direction of q (the v and u blocks are exact: 0 and 2e-3 I). On a free-flyer
  // the gradient at q (+) h e_j is in the tangent at that point, not at q: the difference
  // from d^2 l(q (+) dq) / d dq^2 is first order in h and antisymmetric (a Lie bracket
  // term), so the symmetric part is that Hessian.
  Eigen::MatrixXd exactHessian(const State& s) {
    const int nv = model.nv;
    Eigen::MatrixXd h = hessian;
    Eigen::VectorXd step = Eigen::VectorXd::Zero(nv);
    auto gradientAt = [&](const Eigen::VectorXd& q) {
      pinocchio::computeFrameJacobian(model, data, q, frame, pinocchio::LOCAL_WORLD_ALIGNED, frame_j);
      pinocchio::forwardKinematics(model, data, q);
      pinocchio::updateFramePlacement(model, data, frame);
      return Eigen::VectorXd(2.0 * frame_j.topRows<3>().transpose() * (data.oMf[frame].translation() - target));
    };
    for (int j = 0; j < nv; ++j) {
      step[j] = kHessianStep;
      const Eigen::VectorXd plus = gradientAt(pinocchio::integrate(model, s.q, step));
      step[j] = -kHessianStep;
      const Eigen::VectorXd minus = gradientAt(pinocchio::integrate(model, s.q, step));
      step[j] = 0;
      h.block(0, j, nv, 1) = (plus - minus) / (2 * kHessianStep);
    }
    Eigen::MatrixXd symmetric = 0.5 * (h + h.transpose());
    return symmetric;
  }

  Output output(const std::string& row, const State& s) {
    call(row, s);
    Output o;
    const bool with_cost = row.rfind("step_cost", 0) == 0;
    o.value.resize(model.nq + model.nv + (with_cost ? 1 : 0));
    o.value << q_next, v_next;
    if (with_cost) o.value[model.nq + model.nv] = l;
    if (row == "euler_step_jacobian" || row == "step_cost_derivatives") o.jacobian = J;
    if (row == "step_cost_derivatives") {
      o.gradient = gradient, o.hessian = hessian;
      o.exact_hessian = exactHessian(s);
    }
    return o;
  }
};

}  // namespace

std::vector<RowResult> runPinocchioStep(const pinocchio::Model& model, const State& timed,
                                        const std::vector<State>& checks, const Timing& plan) {
  PinocchioStepRunner runner(model);
  return timeRows(runner, kStepRows, timed, checks, plan);
}

}  // namespace anchors
