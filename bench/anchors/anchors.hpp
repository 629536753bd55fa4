// bench/anchors: what the two anchor sides (Pinocchio's analytic algorithms, and
// CppADCodeGen taping Pinocchio's templates) share: the robot, the states, the rows
// they time, and their results. One row per function of `robodiff bench --json`, with
// the same names (rnea_value, rnea_jacobian_dense, aba_value, aba_jacobian), plus
// crba_value and frame_jacobian_value, which robodiff bench times from specs/ (--spec).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>

#include "commands/bench_timing.hpp"

namespace anchors {

using Timing = robodiff::cli::bench::TimingPlan;

// One state: RNEA reads q, v, a; ABA reads q, v, tau.
struct State {
  Eigen::VectorXd q, v, a, tau;
};

// Draws `count` states from `seed`: q = integrate(neutral, u) with u uniform in [-1, 1]
// (any joint kind, free-flyer included), v, a, tau uniform in [-1, 1].
std::vector<State> drawStates(const pinocchio::Model& model, unsigned seed, int count);

// What a side returns at one state for one function: the value, and the Jacobian
// (nv x 3nv, columns [q (tangent), v, a or tau]) when the function has one.
struct Output {
  Eigen::VectorXd value;
  Eigen::MatrixXd jacobian;  // empty for value rows; for CRBA / frame J the matrix itself
  // The step + cost rows (step_rows.hpp): the cost's gradient w.r.t. [q, v, u] and its
  // Gauss-Newton Hessian; `exact_hessian` only from Pinocchio (central differences of
  // its analytic gradient), what robodiff's exact Hessian is checked against.
  Eigen::VectorXd gradient;
  Eigen::MatrixXd hessian, exact_hessian;
};

// One timed row of a side.
struct RowResult {
  std::string name;
  std::optional<double> us;          // µs per call (empty: not timed)
  std::optional<double> build_s;     // cold build: tape + generate + compile (CppADCodeGen, CasADi)
  std::optional<double> compiler_mib;  // peak memory of the compiler (CppADCodeGen, CasADi)
  std::string status = "ok";         // ok | over_cap | wrong | failed
  std::string note;
  double max_err = 0;                // against Pinocchio's analytic outputs
  std::vector<Output> outputs;       // at the check states
};

// The rows, in order.
extern const std::vector<std::string> kRows;

// max |actual - expected| / max(1, max |expected|) over the whole matrix (as robodiff bench).
double relativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected);

// The frame a frame Jacobian is taken at: the model's last frame (as `robodiff bench`'s
// fk spec picks the robot's last link).
pinocchio::FrameIndex lastFrame(const pinocchio::Model& model);

// Every side's row loop: the runner's outputs at the check states, then its calls timed
// at `timed`. Runner: output(row, state) -> Output, call(row, state).
template <class Runner>
std::vector<RowResult> timeRows(Runner& runner, const std::vector<std::string>& names, const State& timed,
                                const std::vector<State>& checks, const Timing& plan) {
  std::vector<RowResult> rows;
  for (const std::string& name : names) {
    RowResult r;
    r.name = name;
    for (const State& s : checks) r.outputs.push_back(runner.output(name, s));
    r.us = 1e6 * robodiff::cli::bench::secondsPerCall([&] { runner.call(name, timed); }, plan);
    rows.push_back(std::move(r));
  }
  return rows;
}

// Pinocchio on a preallocated Data: its analytic algorithms and derivatives.
std::vector<RowResult> runPinocchio(const pinocchio::Model& model, const State& timed,
                                    const std::vector<State>& checks, const Timing& plan);

// CppADCodeGen: each function taped through Pinocchio's templates, optimized, generated
// as C, compiled with gcc -O2 -march=native into a library of its own under `workdir`,
// and called through its GenericModel. A build longer than `cap_seconds` is stopped and
// reported over the cap. `reuse`: load a library already built there (a second round).
struct CodegenOptions {
  std::string workdir;
  double cap_seconds = 120;
  bool reuse = false;
  std::vector<std::string> only;  // rows to build (empty: all)
  // Also the step rows but step_cost_derivatives (fixed base, nq = nv only).
  bool step_rows = false;
  // Build (or, with reuse, keep) the libraries, neither check nor time them: bench/anchors
  // builds every library first, several at once, then times them with reuse.
  bool build_only = false;
};
// The rows each generated side builds (the step rows only with step_rows).
std::vector<std::string> codegenRowNames(bool step_rows);
std::vector<std::string> casadiRowNames(bool step_rows);

std::vector<RowResult> runCppADCodeGen(const pinocchio::Model& model, const State& timed,
                                       const std::vector<State>& checks, const Timing& plan,
                                       const CodegenOptions& options);

// CasADi: each of the four rows of `robodiff bench` (not CRBA, frame J), and the step rows
// with options.step_rows, as Pinocchio's algorithm on casadi::SX, a casadi::Function (value, or value + SX Jacobian over
// [dq, v, a|tau]), C from casadi::CodeGenerator compiled with gcc -O3 -march=native
// into a library of its own under options.workdir, called through the generated C
// function. Builds, cap and reuse as CppADCodeGen's (casadi_side.cpp).
std::vector<RowResult> runCasadi(const pinocchio::Model& model, const State& timed, const std::vector<State>& checks,
                                 const Timing& plan, const CodegenOptions& options);

// The version of the casadi library anchors_bench links.
std::string casadiVersion();

}  // namespace anchors
