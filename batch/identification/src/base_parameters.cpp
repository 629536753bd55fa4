// Base parameters by QR with column pivoting on a stacked regressor.
#include "robodiff/batch/base_parameters.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "robodiff/batch/identification_error.hpp"
#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/regressor.hpp"

namespace robodiff::batch {

namespace {
constexpr double kCoefficientNoise = 1e-10;  // |K_ij| below this: rounding, set to 0
constexpr double kTieBreak = 1e-6;           // column scale step that decides ties (see below)
}

BaseParameters baseParametersOf(const Eigen::Ref<const Eigen::MatrixXd>& W, double tolerance) {
  const int n = static_cast<int>(W.cols());
  if (W.rows() < W.cols())
    throw IdentificationError("base parameters need at least as many regressor rows (" + std::to_string(W.rows()) +
                              ") as standard parameters (" + std::to_string(n) + ")");
  // Columns often tie exactly (parameters that only ever act together); the pivoting
  // would then pick by rounding noise, so by compiler flags and CPU. Scaling column j by
  // 1 + j * kTieBreak makes the later column win every tie, the same on every build;
  // K is scaled back below.
  const Eigen::VectorXd scale = Eigen::VectorXd::LinSpaced(n, 0.0, n - 1.0) * kTieBreak + Eigen::VectorXd::Ones(n);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(W * scale.asDiagonal());
  const Eigen::MatrixXd R = qr.matrixR().topRows(n).triangularView<Eigen::Upper>();
  const double top = n > 0 ? std::abs(R(0, 0)) : 0.0;
  if (!(top > 0)) throw IdentificationError("the regressor is zero: no inertial parameter affects the torques");
  int r = 0;
  while (r < n && std::abs(R(r, r)) > tolerance * top) ++r;

  BaseParameters base;
  base.standard_count = n;
  base.tolerance = tolerance;
  base.smallest_kept = std::abs(R(r - 1, r - 1)) / top;
  base.largest_dropped = r < n ? std::abs(R(r, r)) / top : 0.0;

  // K in pivoted order, then rows and columns sorted by parameter index.
  const Eigen::MatrixXd K_pivoted =
      R.topLeftCorner(r, r).triangularView<Eigen::Upper>().solve(R.topRightCorner(r, n - r));
  const auto& perm = qr.colsPermutation().indices();
  std::vector<int> ind_order(static_cast<std::size_t>(r)), dep_order(static_cast<std::size_t>(n - r));
  std::iota(ind_order.begin(), ind_order.end(), 0);
  std::iota(dep_order.begin(), dep_order.end(), 0);
  std::sort(ind_order.begin(), ind_order.end(), [&](int a, int b) { return perm[a] < perm[b]; });
  std::sort(dep_order.begin(), dep_order.end(), [&](int a, int b) { return perm[r + a] < perm[r + b]; });
  for (int i : ind_order) base.independent.push_back(perm[i]);
  for (int d : dep_order) base.dependent.push_back(perm[r + d]);
  base.K.resize(r, n - r);
  for (int i = 0; i < r; ++i)
    for (int d = 0; d < n - r; ++d) {
      const int ind = base.independent[static_cast<std::size_t>(i)], dep = base.dependent[static_cast<std::size_t>(d)];
      const double k = K_pivoted(ind_order[static_cast<std::size_t>(i)], dep_order[static_cast<std::size_t>(d)]) *
                       scale[ind] / scale[dep];
      base.K(i, d) = std::abs(k) < kCoefficientNoise ? 0.0 : k;
    }
  base.B = Eigen::MatrixXd::Zero(r, n);
  for (int i = 0; i < r; ++i) {
    base.B(i, base.independent[static_cast<std::size_t>(i)]) = 1.0;
    for (int d = 0; d < n - r; ++d) base.B(i, base.dependent[static_cast<std::size_t>(d)]) = base.K(i, d);
  }
  for (int d = 0; d < n - r; ++d)
    if (base.K.col(d).isZero(0.0)) base.no_effect.push_back(base.dependent[static_cast<std::size_t>(d)]);
  return base;
}

BaseParameters computeBaseParameters(const Model& model, const BaseParameterOptions& options) {
  const int n = kParametersPerBody * model.njoints();
  const int nv = std::max(model.nv, 1);
  const int samples = options.samples > 0 ? options.samples : std::max(20, (4 * n + nv - 1) / nv);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::MatrixXd W(static_cast<Eigen::Index>(samples) * model.nv, n);
  Data<double> data(model);
  for (int k = 0; k < samples; ++k) {
    const Eigen::VectorXd q = randomConfiguration(model, rng);
    Eigen::VectorXd v(model.nv), a(model.nv);
    for (int i = 0; i < model.nv; ++i) v[i] = unit(rng), a[i] = unit(rng);
    W.middleRows(static_cast<Eigen::Index>(k) * model.nv, model.nv) = jointTorqueRegressor(model, data, q, v, a);
  }
  return baseParametersOf(W, options.tolerance);
}

Eigen::VectorXd BaseParameters::complete(const Eigen::VectorXd& base, const Eigen::VectorXd& prior,
                                         const Eigen::VectorXd& scales) const {
  const Eigen::VectorXd gap = base - B * prior;
  const Eigen::VectorXd s2 = scales.size() ? scales.cwiseAbs2().eval() : Eigen::VectorXd::Ones(standard_count).eval();
  const Eigen::MatrixXd BS = B * s2.asDiagonal();
  return prior + BS.transpose() * (BS * B.transpose()).ldlt().solve(gap);
}

std::optional<Eigen::VectorXd> BaseParameters::combinationFor(int i) const {
  const Eigen::VectorXd e = Eigen::VectorXd::Unit(standard_count, i);
  const Eigen::VectorXd c = (B * B.transpose()).ldlt().solve(B * e);
  if ((B.transpose() * c - e).norm() > 1e-9) return std::nullopt;
  return c;
}

std::string BaseParameters::describe(int k, const ParameterLayout& layout) const {
  std::string text = layout.names.at(independent.at(k));
  char buffer[32];
  for (std::size_t d = 0; d < dependent.size(); ++d) {
    const double c = K(k, static_cast<Eigen::Index>(d));
    if (c == 0.0) continue;
    const std::string& name = layout.names.at(dependent[d]);
    text += c < 0 ? " - " : " + ";
    if (std::abs(std::abs(c) - 1.0) > 1e-12) {
      std::snprintf(buffer, sizeof buffer, "%.4g*", std::abs(c));
      text += buffer;
    }
    text += name;
  }
  return text;
}

}  // namespace robodiff::batch
