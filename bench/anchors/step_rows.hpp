// bench/anchors: the user-function rows, one knot of an MPC problem, on a fixed or a
// floating base (a free-flyer: q has nq = nv + 1 coordinates, a unit quaternion).
//
//   euler_step_*: semi-implicit Euler, dt = 0.01 s: v_next = v + dt ABA(q, v, u),
//     q_next = integrate(q, dt v_next). Value [q_next (nq coordinates); v_next]; Jacobian
//     d[q_next (tangent), v_next] / d[q (tangent), v, u], 2nv x 3nv: Pinocchio's dIntegrate
//     conventions (q_next's rows in the tangent at q_next, q's columns in the tangent at q),
//     as crocoddyl's Fx, Fu and robodiff's Jacobians of a configuration.
//   step_cost_*: the same step and the running cost at the knot,
//     l = |p_F(q) - target|^2 + 1e-3 |u|^2 (F: lastFrame), value [q_next; v_next; l];
//     derivatives: the step's Jacobian, l's gradient w.r.t. [q, v, u] (3nv) and its
//     Hessian (3nv x 3nv; Gauss-Newton on the anchors: 2 J^T J + 2e-3 I on u).
//
// The state is the anchors' State with tau as u. Pinocchio composes the step by hand
// (the reference); crocoddyl runs it as an IntegratedActionModelEuler (its cost is
// dt l: its cost, gradient and Hessian are divided by dt for the checks).
#pragma once

#include <array>

#include "anchors.hpp"

namespace anchors {

constexpr double kStepDt = 0.01;
constexpr double kControlWeight = 1e-3;
constexpr std::array<double, 3> kCostTarget = {0.4, 0.1, 0.5};

// The rows, in order (value, then derivative rows).
extern const std::vector<std::string> kStepRows;
// The step rows the generated-code anchors (CppADCodeGen, CasADi) build: all but
// step_cost_derivatives, whose exact Hessian the check (Gauss-Newton Hessians) cannot take.
inline const std::vector<std::string> kGeneratedStepRows = {"euler_step_value", "euler_step_jacobian",
                                                            "step_cost_value"};

inline bool isStepRow(const std::string& row) {
  return row.rfind("euler_step", 0) == 0 || row.rfind("step_cost", 0) == 0;
}

// Pinocchio: aba / computeABADerivatives, dIntegrate, the frame's Jacobian, composed by
// hand on one preallocated Data. Any base.
std::vector<RowResult> runPinocchioStep(const pinocchio::Model& model, const State& timed,
                                        const std::vector<State>& checks, const Timing& plan);

// crocoddyl: StateMultibody, ActuationModelFull, CostModelSum (empty for euler_step;
// frame translation (weight 2) + control (weight 2e-3) residuals for step_cost, so that its
// differential cost is l), DifferentialActionModelFreeFwdDynamics, IntegratedActionModelEuler
// (dt); timed: calc(data, x, u) for value rows, calc + calcDiff for derivative rows.
std::vector<RowResult> runCrocoddyl(const pinocchio::Model& model, const State& timed,
                                    const std::vector<State>& checks, const Timing& plan);

}  // namespace anchors
