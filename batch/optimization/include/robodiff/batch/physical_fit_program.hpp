#pragma once
// The physically consistent inertial-parameter fit as a NonlinearProgram: unconstrained
// in the log-Cholesky coordinates theta (10 per body, physical_log_cholesky.hpp), so any
// iterate is a physically valid robot. The data enter only through the normal equations;
// the objective (least squares, a pull towards the URDF's values and a log-det barrier)
// and its derivatives are derived in docs/physical-fit.md.

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "robodiff/batch/nonlinear_program.hpp"
#include "robodiff/batch/physical_log_cholesky_derivatives.hpp"

namespace robodiff::batch {

// The normal equations of a weighted linear least-squares problem, accumulated block by
// block (so a caller can stream samples without stacking the whole regressor).
struct NormalEquations {
  Eigen::MatrixXd gram;       // G = W^T D W (symmetric, full)
  Eigen::VectorXd moment;     // g = W^T D tau
  double energy = 0;          // c = tau^T D tau
  std::int64_t rows = 0;      // rows of W seen (weighted or not)

  explicit NormalEquations(int parameters = 0);
  // Adds rows of W and tau; `weights` per row (>= 0), empty for all 1. Throws
  // std::invalid_argument for inconsistent sizes, negative or non-finite weights.
  void add(const Eigen::Ref<const Eigen::MatrixXd>& regressor, const Eigen::Ref<const Eigen::VectorXd>& torques,
           const Eigen::Ref<const Eigen::VectorXd>& weights = Eigen::VectorXd());
  // ||W pi - tau||^2_D from the normal equations.
  double residual(const Eigen::VectorXd& parameters) const;
};

NormalEquations normalEquations(const Eigen::Ref<const Eigen::MatrixXd>& regressor,
                                const Eigen::Ref<const Eigen::VectorXd>& torques,
                                const Eigen::Ref<const Eigen::VectorXd>& weights = Eigen::VectorXd());

class PhysicalFitProgram final : public NonlinearProgram {
 public:
  // `prior`: 10 per body (the size of the normal equations); bodies of the prior that are
  // not strictly valid are projected slightly into the valid set for the starting point
  // (projectToStrictlyValid; projectedBodies() lists them); Q pulls towards `prior` as given.
  // Throws std::invalid_argument for inconsistent sizes, non-finite values, lambda < 0 or
  // divergence_weight < 0.
  PhysicalFitProgram(NormalEquations data, Eigen::VectorXd prior, double lambda, double divergence_weight = 1,
                     std::function<bool(const IterationInfo&)> on_iteration = {});

  int bodyCount() const { return bodies_; }
  const Eigen::VectorXd& prior() const { return prior_; }
  const Eigen::VectorXd& regularizationWeights() const { return s_; }  // s_k
  double dataEnergy() const { return energy_; }                           // E
  const std::vector<int>& projectedBodies() const { return projected_; }
  const Eigen::VectorXd& startTheta() const { return theta0_; }

  Eigen::VectorXd parameters(const Eigen::VectorXd& theta) const;  // pi(theta), double-precision map
  double dataResidual(const Eigen::VectorXd& parameters) const;    // ||W pi - tau||^2_D
  // lambda E (Q + w_D sum_b D_b): the regularisation in the data's units (+inf for invalid bodies).
  double regularization(const Eigen::VectorXd& parameters) const;
  const std::vector<Eigen::Matrix4d>& divergenceCentres() const { return centres_; }  // C_b

  int variableCount() const override { return 10 * bodies_; }
  int constraintCount() const override { return 0; }
  void bounds(std::span<double> x_lower, std::span<double> x_upper, std::span<double> g_lower,
              std::span<double> g_upper) const override;
  void startingPoint(std::span<double> x) const override;
  double objective(std::span<const double> x) override;
  void gradient(std::span<const double> x, std::span<double> gradient) override;
  void constraints(std::span<const double>, std::span<double>) override {}
  SparsityEntries constraintJacobianPattern() const override { return {}; }
  void constraintJacobian(std::span<const double>, std::span<double>) override {}
  SparsityEntries hessianPattern() const override;
  void hessian(std::span<const double> x, double objective_factor, std::span<const double> multipliers,
               std::span<double> values) override;
  bool iterationDone(const IterationInfo& info) override;

 private:
  void update(std::span<const double> x);  // pi, J, d f / d pi at x (cached)

  int bodies_ = 0;
  Eigen::MatrixXd gram_;     // G / E
  Eigen::VectorXd moment_;   // g / E
  double energy_ = 1;        // E
  double rest_ = 1;          // c / E
  Eigen::VectorXd prior_, s_, theta0_;
  double lambda_ = 0, divergence_weight_ = 1;
  std::vector<Eigen::Matrix4d> centres_;  // C_b
  Eigen::VectorXd trace_coefficients_;     // a: tr(C_b^-1 J_b) = a_b . pi_b
  double divergence_constant_ = 0;         // sum_b (log det C_b - 4)
  Eigen::MatrixXd curvature_;              // 2 G / E + 2 lambda S
  std::vector<int> projected_;
  std::function<bool(const IterationInfo&)> on_iteration_;
  LogCholeskyDerivatives derivatives_;

  std::vector<double> x_;  // the point of the cache
  Eigen::VectorXd pi_, dpi_;                            // pi(x), d f / d pi
  std::vector<Eigen::Matrix<double, 10, 10>> jacobians_;  // d pi_b / d theta_b
};

}  // namespace robodiff::batch
