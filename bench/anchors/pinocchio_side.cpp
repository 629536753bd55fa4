// The Pinocchio side: its double algorithms and analytic derivatives on one
// preallocated Data, timed like `robodiff bench` (bench_timing.hpp), and its outputs at
// the check states (the reference every other side is checked against).
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/rnea.hpp>

#include <random>

#include "anchors.hpp"

namespace anchors {

const std::vector<std::string> kRows = {"rnea_value",  "rnea_jacobian_dense", "aba_value",
                                        "aba_jacobian", "crba_value",          "frame_jacobian_value"};

std::vector<State> drawStates(const pinocchio::Model& model, unsigned seed, int count) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto draw = [&](int n) {
    Eigen::VectorXd x(n);
    for (int i = 0; i < n; ++i) x[i] = u(rng);
    return x;
  };
  std::vector<State> states;
  for (int k = 0; k < count; ++k) {
    State s;
    s.q = pinocchio::integrate(model, pinocchio::neutral(model), draw(model.nv));
    s.v = draw(model.nv), s.a = draw(model.nv), s.tau = draw(model.nv);
    states.push_back(s);
  }
  return states;
}

double relativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected) {
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols()) return INFINITY;
  if (expected.size() == 0) return 0;
  const double scale = std::max(1.0, expected.cwiseAbs().maxCoeff());
  const double err = (actual - expected).cwiseAbs().maxCoeff() / scale;
  return std::isnan(err) ? INFINITY : err;
}

pinocchio::FrameIndex lastFrame(const pinocchio::Model& model) {
  return static_cast<pinocchio::FrameIndex>(model.nframes - 1);
}

namespace {

using robodiff::cli::bench::doNotOptimize;

// Pinocchio fills only the upper triangle of M and Minv in these algorithms.
Eigen::MatrixXd symmetricFromUpper(const Eigen::MatrixXd& m) {
  Eigen::MatrixXd s = m.selfadjointView<Eigen::Upper>();
  return s;
}

struct PinocchioRunner {
  const pinocchio::Model& model;
  pinocchio::Data data;
  Eigen::MatrixXd d1, d2, d3;
  pinocchio::Data::Matrix6x frame_j;  // the type the wheel's instantiation takes

  explicit PinocchioRunner(const pinocchio::Model& m)
      : model(m), data(m), d1(Eigen::MatrixXd::Zero(m.nv, m.nv)), d2(d1), d3(d1),
        frame_j(pinocchio::Data::Matrix6x::Zero(6, m.nv)) {}

  // One call of `row` at state s (what is timed).
  void call(const std::string& row, const State& s) {
    if (row == "rnea_value") doNotOptimize(pinocchio::rnea(model, data, s.q, s.v, s.a));
    else if (row == "rnea_jacobian_dense") pinocchio::computeRNEADerivatives(model, data, s.q, s.v, s.a, d1, d2, d3);
    else if (row == "aba_value") doNotOptimize(pinocchio::aba(model, data, s.q, s.v, s.tau));
    else if (row == "aba_jacobian") pinocchio::computeABADerivatives(model, data, s.q, s.v, s.tau, d1, d2, d3);
    else if (row == "crba_value") doNotOptimize(pinocchio::crba(model, data, s.q));
    else if (row == "frame_jacobian_value")
      pinocchio::computeFrameJacobian(model, data, s.q, lastFrame(model), pinocchio::LOCAL_WORLD_ALIGNED, frame_j);
    doNotOptimize(data);
  }

  // The outputs of `row` at state s, Jacobians as nv x 3nv [d/dq, d/dv, d/da or d/dtau].
  Output output(const std::string& row, const State& s) {
    call(row, s);
    Output o;
    if (row == "rnea_value") o.value = data.tau;
    if (row == "aba_value") o.value = data.ddq;
    if (row == "rnea_jacobian_dense" || row == "aba_jacobian") {
      o.value = row == "aba_jacobian" ? Eigen::VectorXd(data.ddq) : Eigen::VectorXd(data.tau);
      o.jacobian.resize(model.nv, 3 * model.nv);
      o.jacobian << d1, d2, symmetricFromUpper(d3);
    }
    if (row == "crba_value") o.jacobian = symmetricFromUpper(data.M);
    if (row == "frame_jacobian_value") o.jacobian = frame_j;
    return o;
  }
};

}  // namespace

std::vector<RowResult> runPinocchio(const pinocchio::Model& model, const State& timed,
                                    const std::vector<State>& checks, const Timing& plan) {
  PinocchioRunner runner(model);
  return timeRows(runner, kRows, timed, checks, plan);
}

}  // namespace anchors
