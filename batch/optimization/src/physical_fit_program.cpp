// PhysicalFitProgram: the log-Cholesky fit's objective and its exact derivatives, and the
// normal equations it works on.
#include "robodiff/batch/physical_fit_program.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "robodiff/batch/physical_log_cholesky.hpp"

namespace robodiff::batch {
namespace {

constexpr Eigen::Index kChunkRows = 4096;  // rows of W scaled and multiplied at a time

// a with tr(K J(pi)) = a . pi for a symmetric K (J the pseudo-inertia, linear in pi):
// tr(K_3 Sigma) with Sigma = 0.5 tr(I) 1 - I, plus 2 K_3m . h and K_mm m.
BodyVector<double> traceCoefficients(const Eigen::Matrix4d& k) {
  const double half = 0.5 * k.topLeftCorner<3, 3>().trace();
  BodyVector<double> a;
  a << k(3, 3), 2 * k(0, 3), 2 * k(1, 3), 2 * k(2, 3), half - k(0, 0), -2 * k(0, 1), half - k(1, 1), -2 * k(0, 2),
      -2 * k(1, 2), half - k(2, 2);
  return a;
}

// log det of a body's pseudo-inertia; +inf when it is not positive definite.
double logDetPseudoInertia(const BodyVector<double>& pi) {
  const Eigen::LLT<Eigen::Matrix4d> llt(pseudoInertia(pi));
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const Eigen::Vector4d diagonal = llt.matrixLLT().diagonal();
  if (!(diagonal.array() > 0).all()) return std::numeric_limits<double>::infinity();
  return 2 * diagonal.array().log().sum();
}

// d log det J(theta) / d theta: log det J = 8 alpha + 2 (d1 + d2 + d3).
const BodyVector<double>& logDetGradient() {
  static const BodyVector<double> g = (BodyVector<double>() << 8, 2, 2, 2, 0, 0, 0, 0, 0, 0).finished();
  return g;
}

}  // namespace

NormalEquations::NormalEquations(int parameters)
    : gram(Eigen::MatrixXd::Zero(parameters, parameters)), moment(Eigen::VectorXd::Zero(parameters)) {}

void NormalEquations::add(const Eigen::Ref<const Eigen::MatrixXd>& regressor,
                          const Eigen::Ref<const Eigen::VectorXd>& torques,
                          const Eigen::Ref<const Eigen::VectorXd>& weights) {
  const Eigen::Index n = regressor.cols();
  if (gram.rows() == 0 && rows == 0) *this = NormalEquations(static_cast<int>(n));
  if (n != gram.cols())
    throw std::invalid_argument("normal equations: the regressor has " + std::to_string(n) + " columns, not " +
                                std::to_string(gram.cols()));
  if (torques.size() != regressor.rows())
    throw std::invalid_argument("normal equations: " + std::to_string(torques.size()) + " torques for " +
                                std::to_string(regressor.rows()) + " regressor rows");
  if (weights.size() != 0 && weights.size() != regressor.rows())
    throw std::invalid_argument("normal equations: " + std::to_string(weights.size()) + " weights for " +
                                std::to_string(regressor.rows()) + " rows");
  if (weights.size() != 0 && (!weights.allFinite() || !(weights.array() >= 0).all()))
    throw std::invalid_argument("normal equations: row weights must be finite and >= 0");
  if (!regressor.allFinite() || !torques.allFinite())
    throw std::invalid_argument("normal equations: the regressor or the torques are not all finite");
  Eigen::MatrixXd lower = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index first = 0; first < regressor.rows(); first += kChunkRows) {
    const Eigen::Index k = std::min(kChunkRows, regressor.rows() - first);
    Eigen::MatrixXd w = regressor.middleRows(first, k);
    Eigen::VectorXd t = torques.segment(first, k);
    if (weights.size() != 0) {
      const Eigen::VectorXd root = weights.segment(first, k).cwiseSqrt();
      w = root.asDiagonal() * w;
      t = root.cwiseProduct(t);
    }
    lower.selfadjointView<Eigen::Lower>().rankUpdate(w.transpose());
    moment.noalias() += w.transpose() * t;
    energy += t.squaredNorm();
  }
  gram += Eigen::MatrixXd(lower.selfadjointView<Eigen::Lower>());
  rows += regressor.rows();
}

double NormalEquations::residual(const Eigen::VectorXd& parameters) const {
  return std::max(0.0, parameters.dot(gram * parameters) - 2 * moment.dot(parameters) + energy);
}

NormalEquations normalEquations(const Eigen::Ref<const Eigen::MatrixXd>& regressor,
                                const Eigen::Ref<const Eigen::VectorXd>& torques,
                                const Eigen::Ref<const Eigen::VectorXd>& weights) {
  NormalEquations out(static_cast<int>(regressor.cols()));
  out.add(regressor, torques, weights);
  return out;
}

PhysicalFitProgram::PhysicalFitProgram(NormalEquations data, Eigen::VectorXd prior, double lambda,
                                       double divergence_weight, std::function<bool(const IterationInfo&)> on_iteration)
    : prior_(std::move(prior)), lambda_(lambda), divergence_weight_(divergence_weight),
      on_iteration_(std::move(on_iteration)) {
  const Eigen::Index n = data.gram.rows();
  if (n == 0 || n % 10 != 0 || data.gram.cols() != n || data.moment.size() != n)
    throw std::invalid_argument("physical fit: the normal equations are " + std::to_string(data.gram.rows()) +
                                " x " + std::to_string(data.gram.cols()) + ", not 10 parameters per body");
  if (prior_.size() != n)
    throw std::invalid_argument("physical fit: the prior has " + std::to_string(prior_.size()) +
                                " parameters, the regressor " + std::to_string(n));
  if (!data.gram.allFinite() || !data.moment.allFinite() || !std::isfinite(data.energy) || !prior_.allFinite())
    throw std::invalid_argument("physical fit: the data or the prior are not all finite");
  if (!(lambda >= 0) || !std::isfinite(lambda))
    throw std::invalid_argument("physical fit: the regularisation weight must be finite and >= 0");
  if (!(divergence_weight >= 0) || !std::isfinite(divergence_weight))
    throw std::invalid_argument("physical fit: the divergence weight must be finite and >= 0");
  bodies_ = static_cast<int>(n / 10);
  energy_ = data.energy > 0 ? data.energy : 1.0;
  gram_ = data.gram / energy_;
  moment_ = data.moment / energy_;
  rest_ = data.energy / energy_;

  // Per-body scales from the prior (fallbacks for massless or point-like bodies).
  std::vector<double> mass(bodies_), radius(bodies_);
  double mass_sum = 0, radius_sum = 0;
  int masses = 0, radii = 0;
  for (int b = 0; b < bodies_; ++b) {
    const double m = prior_[10 * b];
    const double r = m > 0 ? std::sqrt(std::max(0.0, prior_[10 * b + 4] + prior_[10 * b + 6] + prior_[10 * b + 9]) /
                                       (2 * m))
                           : 0.0;
    mass[b] = m > 0 ? m : 0.0;
    radius[b] = std::isfinite(r) && r > 0 ? r : 0.0;
    if (mass[b] > 0) mass_sum += mass[b], ++masses;
    if (radius[b] > 0) radius_sum += radius[b], ++radii;
  }
  const double mean_mass = masses > 0 ? mass_sum / masses : 1.0;
  const double mean_radius = radii > 0 ? radius_sum / radii : 0.1;
  s_.resize(n);
  theta0_.resize(n);
  trace_coefficients_.resize(n);
  for (int b = 0; b < bodies_; ++b) {
    const double m = mass[b] > 0 ? mass[b] : mean_mass;
    const double r = std::max(radius[b] > 0 ? radius[b] : mean_radius, 0.01);
    s_.segment<1>(10 * b).setConstant(1 / (m * m));
    s_.segment<3>(10 * b + 1).setConstant(1 / (m * r * m * r));
    s_.segment<6>(10 * b + 4).setConstant(1 / (m * r * r * m * r * r));
    bool changed = false;
    const BodyVector<double> body = prior_.segment<10>(10 * b);
    const BodyVector<double> start = projectToStrictlyValid(body, 1e-3 * mean_mass, &changed);
    if (changed) projected_.push_back(b);
    theta0_.segment<10>(10 * b) = logCholeskyFromParameters(start);
    // The divergence's centre: the prior, or a body of this size when the prior is not valid.
    Eigen::Matrix4d centre = pseudoInertia(body);
    if (changed) {
      centre.setZero();
      centre.topLeftCorner<3, 3>().diagonal().setConstant(m * r * r / 3);
      centre(3, 3) = m;
    }
    centres_.push_back(centre);
    const Eigen::Matrix4d inverse = centre.inverse();
    trace_coefficients_.segment<10>(10 * b) = traceCoefficients(0.5 * (inverse + inverse.transpose()));
    divergence_constant_ += std::log(centre.determinant()) - 4;
  }
  curvature_ = 2 * gram_;
  curvature_.diagonal() += 2 * lambda_ * s_;
  jacobians_.resize(bodies_);
}

Eigen::VectorXd PhysicalFitProgram::parameters(const Eigen::VectorXd& theta) const {
  if (theta.size() != 10 * bodies_)
    throw std::invalid_argument("physical fit: theta has " + std::to_string(theta.size()) + " entries, not " +
                                std::to_string(10 * bodies_));
  Eigen::VectorXd pi(theta.size());
  for (int b = 0; b < bodies_; ++b)
    pi.segment<10>(10 * b) = parametersFromLogCholesky<double>(theta.segment<10>(10 * b));
  return pi;
}

double PhysicalFitProgram::dataResidual(const Eigen::VectorXd& pi) const {
  return std::max(0.0, pi.dot(gram_ * pi) - 2 * moment_.dot(pi) + rest_) * energy_;
}

double PhysicalFitProgram::regularization(const Eigen::VectorXd& pi) const {
  double divergence = divergence_constant_ + trace_coefficients_.dot(pi);
  for (int b = 0; b < bodies_; ++b) divergence -= logDetPseudoInertia(pi.segment<10>(10 * b));
  return lambda_ * energy_ * (s_.dot((pi - prior_).cwiseAbs2()) + divergence_weight_ * divergence);
}

void PhysicalFitProgram::bounds(std::span<double> x_lower, std::span<double> x_upper, std::span<double>,
                                std::span<double>) const {
  std::fill(x_lower.begin(), x_lower.end(), -std::numeric_limits<double>::infinity());
  std::fill(x_upper.begin(), x_upper.end(), std::numeric_limits<double>::infinity());
}

void PhysicalFitProgram::startingPoint(std::span<double> x) const {
  std::copy(theta0_.data(), theta0_.data() + theta0_.size(), x.begin());
}

void PhysicalFitProgram::update(std::span<const double> x) {
  if (x_.size() == x.size() && std::equal(x.begin(), x.end(), x_.begin())) return;
  pi_.resize(10 * bodies_);
  for (int b = 0; b < bodies_; ++b) {
    const Eigen::Map<const Eigen::Matrix<double, 10, 1>> theta(x.data() + 10 * b);
    Eigen::Matrix<double, 10, 1> pi;
    derivatives_.valueAndJacobian(theta, pi, jacobians_[b]);
    pi_.segment<10>(10 * b) = pi;
  }
  dpi_ = 2 * (gram_ * pi_ - moment_) +
         lambda_ * (2 * s_.cwiseProduct(pi_ - prior_) + divergence_weight_ * trace_coefficients_);
  x_.assign(x.begin(), x.end());
}

double PhysicalFitProgram::objective(std::span<const double> x) {
  update(x);
  double divergence = divergence_constant_ + trace_coefficients_.dot(pi_);
  for (int b = 0; b < bodies_; ++b)
    divergence -= logDetGradient().dot(Eigen::Map<const BodyVector<double>>(x.data() + 10 * b));
  return pi_.dot(gram_ * pi_) - 2 * moment_.dot(pi_) + rest_ +
         lambda_ * (s_.dot((pi_ - prior_).cwiseAbs2()) + divergence_weight_ * divergence);
}

void PhysicalFitProgram::gradient(std::span<const double> x, std::span<double> gradient) {
  update(x);
  for (int b = 0; b < bodies_; ++b)
    Eigen::Map<Eigen::Matrix<double, 10, 1>>(gradient.data() + 10 * b) =
        jacobians_[b].transpose() * dpi_.segment<10>(10 * b) - lambda_ * divergence_weight_ * logDetGradient();
}

SparsityEntries PhysicalFitProgram::hessianPattern() const {
  SparsityEntries entries;
  const int n = 10 * bodies_;
  entries.reserve(static_cast<std::size_t>(n) * (n + 1) / 2);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c <= r; ++c) entries.emplace_back(r, c);
  return entries;
}

void PhysicalFitProgram::hessian(std::span<const double> x, double objective_factor, std::span<const double>,
                                 std::span<double> values) {
  update(x);
  const int n = 10 * bodies_;
  // J^T (2 G / E + 2 lambda S) J, block by block (J is block diagonal), lower blocks only.
  Eigen::MatrixXd h(n, n);
  for (int a = 0; a < bodies_; ++a)
    for (int b = 0; b <= a; ++b)
      h.block<10, 10>(10 * a, 10 * b) =
          jacobians_[a].transpose() * curvature_.block<10, 10>(10 * a, 10 * b) * jacobians_[b];
  // The curvature of the map, weighted by d f / d pi.
  for (int b = 0; b < bodies_; ++b) {
    const Eigen::Map<const Eigen::Matrix<double, 10, 1>> theta(x.data() + 10 * b);
    h.block<10, 10>(10 * b, 10 * b) += derivatives_.weightedHessian(theta, dpi_.segment<10>(10 * b));
  }
  std::size_t k = 0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c <= r; ++c) values[k++] = objective_factor * h(r, c);
}

bool PhysicalFitProgram::iterationDone(const IterationInfo& info) {
  return on_iteration_ ? on_iteration_(info) : true;
}

}  // namespace robodiff::batch
