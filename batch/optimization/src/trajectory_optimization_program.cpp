// TrajectoryProgram: the values and exact derivatives of a trajectory optimisation from
// batches of generated-function evaluations over all knots, through the chain rule of
// the finite-difference stencil.
#include "robodiff/batch/trajectory_optimization_program.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "trajopt_discretization.hpp"
#include "trajopt_hessian_band.hpp"

namespace robodiff::batch {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
using Clock = std::chrono::steady_clock;
using ConstRowMajor = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
using ConstVector = Eigen::Map<const Eigen::VectorXd>;

// A limited quantity of one knot's joint: one row of g, |value| <= limit.
struct LimitRow {
  int knot = 0, joint = 0;
  double limit = kInfinity;
};

// Adds the seconds of its life to `total`.
class EvaluationTimer {
 public:
  explicit EvaluationTimer(double& total) : total_(total), start_(Clock::now()) {}
  ~EvaluationTimer() { total_ += std::chrono::duration<double>(Clock::now() - start_).count(); }
  EvaluationTimer(const EvaluationTimer&) = delete;
  EvaluationTimer& operator=(const EvaluationTimer&) = delete;

 private:
  double& total_;
  Clock::time_point start_;
};

bool limited(double limit) { return std::isfinite(limit) && limit > 0; }

}  // namespace

struct TrajectoryProgram::Impl {
  Impl(const Model& model, const TrajectoryFunctions& functions, const TrajectoryOptimizationOptions& options);

  int T, nv;
  TrajectoryOptimizationOptions options;
  TrajectoryFunctions functions;
  TimeDiscretization grid;
  bool dynamics_in_hessian;  // w > 0 or torque limits: the RNEA terms enter the Hessian
  HessianBand band;
  Eigen::VectorXd lower, upper, velocity_limit, effort_limit;
  std::vector<LimitRow> velocity_rows, torque_rows;
  std::vector<int> torque_row_of;  // knot * nv + joint -> index in torque_rows, or -1

  // The first-order function's layout, and its batch at the cached x.
  std::size_t in1 = 0, out1 = 0, q1 = 0, v1 = 0, a1 = 0, tau1 = 0, jac1 = 0;
  std::vector<double> in_first, out_first, x_cached;
  bool cached = false;
  // The second-order function's layout and batch.
  std::size_t in2 = 0, out2 = 0, q2 = 0, v2 = 0, a2 = 0, w2 = 0, hess2 = 0;
  std::vector<std::uint32_t> hess_row_ptr, hess_col_idx;
  std::vector<double> in_second, out_second;

  double evaluation_seconds = 0;
  int first_evaluations = 0, second_evaluations = 0;

  // Knot k's q, v, a from the positions x through the stencil.
  void knotState(int k, std::span<const double> x, double* q, double* v, double* a) const {
    std::fill_n(q, nv, 0.0);
    std::fill_n(v, nv, 0.0);
    std::fill_n(a, nv, 0.0);
    for (const StencilTerm& t : grid.stencil(k)) {
      const double* xj = x.data() + static_cast<std::size_t>(t.knot) * nv;
      for (int i = 0; i < nv; ++i) {
        q[i] += t.q * xj[i];
        v[i] += t.v * xj[i];
        a[i] += t.a * xj[i];
      }
    }
  }

  // Evaluates tau and its Jacobian at every knot, unless x is the point of the last call.
  void firstOrderAt(std::span<const double> x) {
    if (x.size() != static_cast<std::size_t>(T) * nv)
      throw std::invalid_argument("trajectory optimisation: x has " + std::to_string(x.size()) + " entries, not " +
                                  std::to_string(T) + " knots x " + std::to_string(nv) + " joints");
    if (cached && std::equal(x.begin(), x.end(), x_cached.begin())) return;
    EvaluationTimer timer(evaluation_seconds);
    for (int k = 0; k < T; ++k) {
      double* in = in_first.data() + k * in1;
      knotState(k, x, in + q1, in + v1, in + a1);
    }
    functions.firstOrder().evaluateMany(static_cast<std::uint64_t>(T), in_first.data(), out_first.data());
    x_cached.assign(x.begin(), x.end());
    cached = true;
    ++first_evaluations;
  }

  ConstVector q(int k) const { return ConstVector(in_first.data() + k * in1 + q1, nv); }
  ConstVector v(int k) const { return ConstVector(in_first.data() + k * in1 + v1, nv); }
  ConstVector a(int k) const { return ConstVector(in_first.data() + k * in1 + a1, nv); }
  ConstVector tau(int k) const { return ConstVector(out_first.data() + k * out1 + tau1, nv); }
  ConstRowMajor jacobian(int k) const { return ConstRowMajor(out_first.data() + k * out1 + jac1, nv, 3 * nv); }

  TrajectoryCost cost() const {
    TrajectoryCost c;
    for (int k = 0; k < T; ++k) {
      const double weight = grid.quadratureWeight(k);
      c.smoothness += options.smoothness_weight * weight * a(k).squaredNorm();
      c.torque += options.torque_weight * weight * tau(k).squaredNorm();
    }
    c.total = c.smoothness + c.torque;
    return c;
  }
};

TrajectoryProgram::Impl::Impl(const Model& model, const TrajectoryFunctions& functions_in,
                              const TrajectoryOptimizationOptions& options_in)
    : T(options_in.knots), nv(model.nv), options(options_in), functions(functions_in),
      grid(options_in.knots, options_in.duration / (options_in.knots - 1)),
      dynamics_in_hessian(options_in.torque_weight > 0 || options_in.torque_limits),
      band(options_in.knots, model.nv, dynamics_in_hessian), lower(model.lowerPositionLimit()),
      upper(model.upperPositionLimit()), velocity_limit(model.velocityLimit()),
      effort_limit(options_in.effort_limit.size() ? options_in.effort_limit : model.effortLimit()) {
  // Velocity rows: interior knots (the ends are at rest), joints with a finite limit.
  if (options.velocity_limits)
    for (int k = 1; k < T - 1; ++k)
      for (int i = 0; i < nv; ++i)
        if (limited(velocity_limit[i])) velocity_rows.push_back({k, i, velocity_limit[i]});
  torque_row_of.assign(static_cast<std::size_t>(T) * nv, -1);
  if (options.torque_limits)
    for (int k = 0; k < T; ++k)
      for (int i = 0; i < nv; ++i)
        if (limited(effort_limit[i])) {
          torque_row_of[k * nv + i] = static_cast<int>(torque_rows.size());
          torque_rows.push_back({k, i, effort_limit[i]});
        }

  const BatchFunction& first = functions.firstOrder();
  in1 = first.inputCount(), out1 = first.outputCount();
  q1 = first.input("q").offset, v1 = first.input("v").offset, a1 = first.input("a").offset;
  tau1 = first.output("value").offset, jac1 = first.output("jacobian").offset;
  const BlockLayout& jac = first.output("jacobian");
  if (first.input("q").size != static_cast<std::uint32_t>(nv) || jac.sparse || jac.cols != 3u * nv)
    throw std::invalid_argument("trajectory optimisation: the first-order function does not fit the model (nv = " +
                                std::to_string(nv) + ")");
  in_first.resize(static_cast<std::size_t>(T) * in1);
  out_first.resize(static_cast<std::size_t>(T) * out1);

  const BatchFunction& second = functions.secondOrder();
  in2 = second.inputCount(), out2 = second.outputCount();
  q2 = second.input("q").offset, v2 = second.input("v").offset, a2 = second.input("a").offset;
  w2 = second.input("weights").offset;
  const BlockLayout& hess = second.output("hessian");
  if (!hess.sparse || hess.rows != 3u * nv)
    throw std::invalid_argument("trajectory optimisation: the second-order function does not fit the model (nv = " +
                                std::to_string(nv) + ")");
  hess2 = hess.offset;
  hess_row_ptr = hess.row_ptr;
  hess_col_idx = hess.col_idx;
  in_second.resize(static_cast<std::size_t>(T) * in2);
  out_second.resize(static_cast<std::size_t>(T) * out2);
}

TrajectoryProgram::TrajectoryProgram(const Model& model, const TrajectoryFunctions& functions,
                                     const TrajectoryOptimizationOptions& options) {
  checkTrajectoryOptions(model, options);
  impl_ = std::make_unique<Impl>(model, functions, options);
}

TrajectoryProgram::~TrajectoryProgram() = default;

int TrajectoryProgram::variableCount() const { return impl_->T * impl_->nv; }

int TrajectoryProgram::constraintCount() const {
  return static_cast<int>(impl_->velocity_rows.size() + impl_->torque_rows.size());
}

int TrajectoryProgram::knots() const { return impl_->T; }
double TrajectoryProgram::timeStep() const { return impl_->grid.step(); }
int TrajectoryProgram::velocityConstraintCount() const { return static_cast<int>(impl_->velocity_rows.size()); }
double TrajectoryProgram::evaluationSeconds() const { return impl_->evaluation_seconds; }
int TrajectoryProgram::firstOrderEvaluations() const { return impl_->first_evaluations; }
int TrajectoryProgram::secondOrderEvaluations() const { return impl_->second_evaluations; }

void TrajectoryProgram::bounds(std::span<double> x_lower, std::span<double> x_upper, std::span<double> g_lower,
                               std::span<double> g_upper) const {
  const Impl& p = *impl_;
  for (int k = 0; k < p.T; ++k)
    for (int i = 0; i < p.nv; ++i) {
      const std::size_t n = static_cast<std::size_t>(k) * p.nv + i;
      // The ends are fixed by equal bounds; the interior within the position limits.
      if (k == 0) x_lower[n] = x_upper[n] = p.options.q0[i];
      else if (k == p.T - 1) x_lower[n] = x_upper[n] = p.options.qT[i];
      else x_lower[n] = p.lower[i], x_upper[n] = p.upper[i];
    }
  std::size_t row = 0;
  for (const LimitRow& r : p.velocity_rows) g_lower[row] = -r.limit, g_upper[row++] = r.limit;
  for (const LimitRow& r : p.torque_rows) g_lower[row] = -r.limit, g_upper[row++] = r.limit;
}

void TrajectoryProgram::startingPoint(std::span<double> x) const {
  const Impl& p = *impl_;
  for (int k = 0; k < p.T; ++k)
    for (int i = 0; i < p.nv; ++i) {
      const double s = static_cast<double>(k) / (p.T - 1);
      x[static_cast<std::size_t>(k) * p.nv + i] = p.options.initial_guess.size()
                                                      ? p.options.initial_guess(k, i)
                                                      : (1 - s) * p.options.q0[i] + s * p.options.qT[i];
    }
}

double TrajectoryProgram::objective(std::span<const double> x) {
  impl_->firstOrderAt(x);
  return impl_->cost().total;
}

void TrajectoryProgram::gradient(std::span<const double> x, std::span<double> gradient) {
  Impl& p = *impl_;
  p.firstOrderAt(x);
  EvaluationTimer timer(p.evaluation_seconds);
  const int nv = p.nv;
  std::fill(gradient.begin(), gradient.end(), 0.0);
  Eigen::VectorXd gz(3 * nv);  // d cost_k / d z_k
  for (int k = 0; k < p.T; ++k) {
    const double c = p.grid.quadratureWeight(k);
    gz.setZero();
    if (p.options.torque_weight > 0)
      gz.noalias() = (2 * p.options.torque_weight * c) * (p.jacobian(k).transpose() * p.tau(k));
    gz.tail(nv) += (2 * p.options.smoothness_weight * c) * p.a(k);
    for (const StencilTerm& t : p.grid.stencil(k))
      for (int i = 0; i < nv; ++i)
        gradient[static_cast<std::size_t>(t.knot) * nv + i] += t.q * gz[i] + t.v * gz[nv + i] + t.a * gz[2 * nv + i];
  }
}

void TrajectoryProgram::constraints(std::span<const double> x, std::span<double> g) {
  Impl& p = *impl_;
  p.firstOrderAt(x);
  std::size_t row = 0;
  for (const LimitRow& r : p.velocity_rows) g[row++] = p.v(r.knot)[r.joint];
  for (const LimitRow& r : p.torque_rows) g[row++] = p.tau(r.knot)[r.joint];
}

SparsityEntries TrajectoryProgram::constraintJacobianPattern() const {
  const Impl& p = *impl_;
  SparsityEntries entries;
  int row = 0;
  // v_k = (q_{k+1} - q_{k-1}) / 2h on interior knots.
  for (const LimitRow& r : p.velocity_rows) {
    entries.emplace_back(row, (r.knot - 1) * p.nv + r.joint);
    entries.emplace_back(row, (r.knot + 1) * p.nv + r.joint);
    ++row;
  }
  // tau_k depends on every joint of the knots of its stencil.
  for (const LimitRow& r : p.torque_rows) {
    for (const StencilTerm& t : p.grid.stencil(r.knot))
      for (int j = 0; j < p.nv; ++j) entries.emplace_back(row, t.knot * p.nv + j);
    ++row;
  }
  return entries;
}

void TrajectoryProgram::constraintJacobian(std::span<const double> x, std::span<double> values) {
  Impl& p = *impl_;
  p.firstOrderAt(x);
  const double half_inverse_step = 1 / (2 * p.grid.step());
  std::size_t n = 0;
  for (std::size_t r = 0; r < p.velocity_rows.size(); ++r) {
    values[n++] = -half_inverse_step;
    values[n++] = half_inverse_step;
  }
  for (const LimitRow& r : p.torque_rows) {
    const ConstRowMajor J = p.jacobian(r.knot);
    for (const StencilTerm& t : p.grid.stencil(r.knot))
      for (int j = 0; j < p.nv; ++j)
        values[n++] = t.q * J(r.joint, j) + t.v * J(r.joint, p.nv + j) + t.a * J(r.joint, 2 * p.nv + j);
  }
}

SparsityEntries TrajectoryProgram::hessianPattern() const { return impl_->band.entries(); }

void TrajectoryProgram::hessian(std::span<const double> x, double objective_factor,
                                std::span<const double> multipliers, std::span<double> values) {
  Impl& p = *impl_;
  p.firstOrderAt(x);
  EvaluationTimer timer(p.evaluation_seconds);
  const int nv = p.nv, nz = 3 * nv;
  const double w = p.options.torque_weight, s = p.options.smoothness_weight;
  std::fill(values.begin(), values.end(), 0.0);

  // The weights of the second-order terms, mu_k = sigma 2 w c_k tau_k + lambda_k, and
  // their Hessians for all knots in one batch (skipped when every weight is zero).
  const std::size_t torque_row0 = p.velocity_rows.size();
  bool second_order = false;
  for (int k = 0; k < p.T && p.dynamics_in_hessian; ++k) {
    double* in = p.in_second.data() + k * p.in2;
    std::copy_n(p.q(k).data(), nv, in + p.q2);
    std::copy_n(p.v(k).data(), nv, in + p.v2);
    std::copy_n(p.a(k).data(), nv, in + p.a2);
    const double factor = objective_factor * 2 * w * p.grid.quadratureWeight(k);
    for (int i = 0; i < nv; ++i) {
      const int row = p.torque_row_of[k * nv + i];
      double& mu = in[p.w2 + i];
      mu = factor * p.tau(k)[i] + (row >= 0 ? multipliers[torque_row0 + row] : 0.0);
      second_order = second_order || mu != 0;
    }
  }
  if (second_order) {
    p.functions.secondOrder().evaluateMany(static_cast<std::uint64_t>(p.T), p.in_second.data(),
                                           p.out_second.data());
    ++p.second_evaluations;
  }

  Eigen::MatrixXd K(nz, nz), B(nv, nv);
  for (int k = 0; k < p.T; ++k) {
    // K_k: the Hessian of knot k's terms of the Lagrangian in z_k = (q_k, v_k, a_k).
    const double c = p.grid.quadratureWeight(k);
    K.setZero();
    if (w > 0 && objective_factor != 0) {
      const ConstRowMajor J = p.jacobian(k);
      K.noalias() = (objective_factor * 2 * w * c) * (J.transpose() * J);
    }
    if (second_order) {
      const double* h = p.out_second.data() + k * p.out2 + p.hess2;
      for (int r = 0; r < nz; ++r)
        for (std::uint32_t e = p.hess_row_ptr[r]; e < p.hess_row_ptr[r + 1]; ++e) {
          const int col = static_cast<int>(p.hess_col_idx[e]);
          K(r, col) += h[e];
          if (col != r) K(col, r) += h[e];
        }
    }
    K.diagonal().tail(nv).array() += objective_factor * 2 * s * c;

    // Through the stencil: the block of knots (j1, j2) is S_j1^T K S_j2; lower triangle only.
    const std::vector<StencilTerm>& stencil = p.grid.stencil(k);
    for (const StencilTerm& t1 : stencil)
      for (const StencilTerm& t2 : stencil) {
        if (t1.knot < t2.knot) continue;
        const double c1[3] = {t1.q, t1.v, t1.a}, c2[3] = {t2.q, t2.v, t2.a};
        B.setZero();
        for (int b1 = 0; b1 < 3; ++b1)
          for (int b2 = 0; b2 < 3; ++b2)
            if (c1[b1] != 0 && c2[b2] != 0) B += (c1[b1] * c2[b2]) * K.block(b1 * nv, b2 * nv, nv, nv);
        for (int i1 = 0; i1 < nv; ++i1)
          for (int i2 = 0; i2 < nv; ++i2) {
            if (t1.knot == t2.knot && i2 > i1) continue;
            const int index = p.band.index(t1.knot, i1, t2.knot, i2);
            if (index >= 0) values[index] += B(i1, i2);  // absent: a structural zero (no dynamics)
          }
      }
  }
}

bool TrajectoryProgram::iterationDone(const IterationInfo& info) {
  return !impl_->options.on_iteration || impl_->options.on_iteration(info);
}

Trajectory TrajectoryProgram::trajectoryAt(std::span<const double> x) {
  Impl& p = *impl_;
  p.firstOrderAt(x);
  Trajectory t;
  t.time.resize(p.T);
  t.q.resize(p.T, p.nv), t.v.resize(p.T, p.nv), t.a.resize(p.T, p.nv), t.tau.resize(p.T, p.nv);
  for (int k = 0; k < p.T; ++k) {
    t.time[k] = k * p.grid.step();
    t.q.row(k) = p.q(k).transpose();
    t.v.row(k) = p.v(k).transpose();
    t.a.row(k) = p.a(k).transpose();
    t.tau.row(k) = p.tau(k).transpose();
  }
  return t;
}

TrajectoryCost TrajectoryProgram::costAt(std::span<const double> x) {
  impl_->firstOrderAt(x);
  return impl_->cost();
}

LimitViolation TrajectoryProgram::violationAt(std::span<const double> x) {
  Impl& p = *impl_;
  p.firstOrderAt(x);
  LimitViolation worst;
  for (int k = 0; k < p.T; ++k)
    for (int i = 0; i < p.nv; ++i) {
      const double q = p.q(k)[i];
      worst.position = std::max({worst.position, p.lower[i] - q, q - p.upper[i]});
      if (limited(p.velocity_limit[i]))
        worst.velocity = std::max(worst.velocity, std::abs(p.v(k)[i]) - p.velocity_limit[i]);
      if (limited(p.effort_limit[i])) worst.torque = std::max(worst.torque, std::abs(p.tau(k)[i]) - p.effort_limit[i]);
    }
  return worst;
}

}  // namespace robodiff::batch
