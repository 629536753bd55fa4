// The crocoddyl side of the step rows (step_rows.hpp): the knot as crocoddyl builds it
// for an MPC (a free forward-dynamics differential action, Euler-integrated), with one
// preallocated action data, timed like `robodiff bench`: calc(data, x, u) for the value
// rows, calc then calcDiff for the derivative rows (as crocoddyl's own benchmarks).
#include <crocoddyl/core/costs/cost-sum.hpp>
#include <crocoddyl/core/costs/residual.hpp>
#include <crocoddyl/core/integrator/euler.hpp>
#include <crocoddyl/core/residuals/control.hpp>
#include <crocoddyl/multibody/actions/free-fwddyn.hpp>
#include <crocoddyl/multibody/actuations/full.hpp>
#include <crocoddyl/multibody/residuals/frame-translation.hpp>
#include <crocoddyl/multibody/states/multibody.hpp>

#include "step_rows.hpp"

namespace anchors {
namespace {

using robodiff::cli::bench::doNotOptimize;

// One Euler-integrated knot, with or without the running cost.
struct CrocoddylKnot {
  std::shared_ptr<crocoddyl::StateMultibody> state;
  std::shared_ptr<crocoddyl::IntegratedActionModelEuler> action;
  std::shared_ptr<crocoddyl::ActionDataAbstract> data;

  CrocoddylKnot(const pinocchio::Model& model, bool with_cost) {
    state = std::make_shared<crocoddyl::StateMultibody>(std::make_shared<pinocchio::Model>(model));
    auto actuation = std::make_shared<crocoddyl::ActuationModelFull>(state);
    const std::size_t nu = actuation->get_nu();
    auto costs = std::make_shared<crocoddyl::CostModelSum>(state, nu);
    if (with_cost) {
      // Quadratic activations are |r|^2 / 2: weights 2 and 2e-3 make the cost l.
      const Eigen::Vector3d target(kCostTarget[0], kCostTarget[1], kCostTarget[2]);
      costs->addCost("frame", std::make_shared<crocoddyl::CostModelResidual>(
                                  state, std::make_shared<crocoddyl::ResidualModelFrameTranslation>(
                                             state, lastFrame(model), target, nu)),
                     2.0);
      costs->addCost("control", std::make_shared<crocoddyl::CostModelResidual>(
                                    state, std::make_shared<crocoddyl::ResidualModelControl>(state, nu)),
                     2.0 * kControlWeight);
    }
    auto dynamics = std::make_shared<crocoddyl::DifferentialActionModelFreeFwdDynamics>(state, actuation, costs);
    action = std::make_shared<crocoddyl::IntegratedActionModelEuler>(dynamics, kStepDt);
    data = action->createData();
  }
};

struct CrocoddylRunner {
  const pinocchio::Model& model;
  CrocoddylKnot step, step_cost;
  Eigen::VectorXd x;

  explicit CrocoddylRunner(const pinocchio::Model& m)
      : model(m), step(m, false), step_cost(m, true), x(m.nq + m.nv) {}

  static bool withCost(const std::string& row) { return row.rfind("step_cost", 0) == 0; }
  static bool derivatives(const std::string& row) {
    return row == "euler_step_jacobian" || row == "step_cost_derivatives";
  }

  void call(const std::string& row, const State& s) {
    CrocoddylKnot& k = withCost(row) ? step_cost : step;
    x << s.q, s.v;
    k.action->calc(k.data, x, s.tau);
    if (derivatives(row)) k.action->calcDiff(k.data, x, s.tau);
    doNotOptimize(*k.data);
  }

  // Its outputs in the rows' terms: x_next, [Fx Fu], and the cost, [Lx; Lu] and
  // [Lxx Lxu; Lux Luu] divided by dt (crocoddyl's integrated cost is dt l).
  Output output(const std::string& row, const State& s) {
    call(row, s);
    const crocoddyl::ActionDataAbstract& d = *(withCost(row) ? step_cost : step).data;
    const int nv = model.nv, nx = 2 * nv;
    Output o;
    o.value.resize(model.nq + nv + (withCost(row) ? 1 : 0));
    o.value.head(model.nq + nv) = d.xnext;
    if (withCost(row)) o.value[model.nq + nv] = d.cost / kStepDt;
    if (!derivatives(row)) return o;
    o.jacobian.resize(nx, nx + nv);
    o.jacobian << d.Fx, d.Fu;
    if (row != "step_cost_derivatives") return o;
    o.gradient.resize(nx + nv);
    o.gradient << d.Lx, d.Lu;
    o.gradient /= kStepDt;
    o.hessian.resize(nx + nv, nx + nv);
    o.hessian << d.Lxx, d.Lxu, d.Lxu.transpose(), d.Luu;
    o.hessian /= kStepDt;
    return o;
  }
};

}  // namespace

std::vector<RowResult> runCrocoddyl(const pinocchio::Model& model, const State& timed,
                                    const std::vector<State>& checks, const Timing& plan) {
  CrocoddylRunner runner(model);
  return timeRows(runner, kStepRows, timed, checks, plan);
}

}  // namespace anchors
