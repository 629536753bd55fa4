#pragma once
// The physically consistent inertial-parameter fit as a NonlinearProgram: unconstrained
// in the log-Cholesky coordinates theta (10 per body, physical_log_cholesky.hpp), so any
// iterate is a physically valid robot.
//
// The data enter only through the normal equations of the weighted least-squares problem
//   ||W pi - tau||^2_D = pi^T G pi - 2 g^T pi + c,   G = W^T D W, g = W^T D tau, c = tau^T D tau
// (D = diag(row weights)), so the solver never touches the (N nv) x (10 nb) regressor W.
//
// Objective (normalised by the data's energy E = c, so that it is about 1 at pi = 0 and
// Ipopt's tolerances mean the same for 100 or 100,000 samples):
//   f(theta) = ||W pi(theta) - tau||^2_D / E + lambda (Q(pi) + w_D sum_b D_b(theta_b))
//
// Q: the quadratic pull towards the prior pi0 (the URDF's values),
//   Q(pi) = sum_k s_k (pi_k - pi0_k)^2,  s_k = 1 / scale_k^2,
// with, per body b, the scales   mass: m_b,  first moment: m_b r_b,  rotational inertia: m_b r_b^2,
// m_b the prior mass and r_b = sqrt(tr(I_o) / (2 m_b)) the RMS distance of the prior's mass
// from the joint frame's origin (at least 1 cm; a massless prior takes the mean of the
// others' mass and radius). So Q counts deviations relative to each body's own size, and
// lambda is the cost, as a fraction of the torques' sum of squares, of moving one parameter
// by its body's scale.
//
// D_b: the log-det (Bregman) divergence of the body's pseudo-inertia J_b from a centre C_b
// (the geometric prior of Lee & Wensing 2020, paired with log-Cholesky by Rucker & Wensing 2022),
//   D_b = tr(C_b^-1 J_b) - log det(C_b^-1 J_b) - 4  >= 0,  0 only at J_b = C_b,
// C_b the prior body when it is strictly valid, else a body of mass m_b spread isotropically
// with RMS radius r_b about the origin. It is a barrier: it grows without bound towards the
// boundary of the valid set, so the optimum is strictly inside it even when the data (and Q)
// would rather have a degenerate body, and theta stays finite. In theta it is cheap:
// tr(C^-1 J) is linear in pi, and log det J(theta) = 8 alpha + 2 (d1 + d2 + d3) exactly.
// w_D (default 1) weighs it against Q; 0 leaves Q alone (boundary optima then make theta
// drift towards infinity, and bodies numerically flat).
//
// Derivatives: pi(theta) is body by body, its Jacobian J (block diagonal) and weighted
// Hessians come from robodiff's generated code (physical_log_cholesky_derivatives.hpp); with
//   p = d f / d pi = 2 (G pi - g) / E + lambda (2 S (pi - pi0) + w_D a),  a_b = d tr(C_b^-1 J_b) / d pi_b,
//   grad f = J^T p - lambda w_D d(sum_b log det J_b) / d theta,
//   hess f = J^T (2 G / E + 2 lambda S) J + blockdiag_b(sum_k p_k d^2 pi_k / d theta_b^2),
// dense across bodies through G (the lower triangle is given to Ipopt).

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
