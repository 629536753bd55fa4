// Ordinary and weighted least squares on the base regressor, with covariance.
#include "robodiff/batch/least_squares.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "robodiff/batch/identification_error.hpp"

namespace robodiff::batch {
namespace {

struct Solved {
  Eigen::VectorXd theta, residual;  // residual of the (weighted) rows
  Eigen::MatrixXd covariance;
  double sigma = 0, condition = 0;
};

// One (weighted) fit: rows of joint j scaled by row_weight[j].
Solved fit(const Eigen::MatrixXd& W, const Eigen::VectorXd& tau, int nv, const Eigen::VectorXd& row_weight,
           const LeastSquaresOptions& options, const std::vector<std::string>& names) {
  const Eigen::Index m = W.rows(), r = W.cols();
  Eigen::MatrixXd Ww = W;
  Eigen::VectorXd tw = tau;
  for (Eigen::Index i = 0; i < m; ++i) {
    const double w = row_weight[i % nv];
    Ww.row(i) *= w;
    tw[i] *= w;
  }
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(Ww);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(r).triangularView<Eigen::Upper>();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullV);
  const Eigen::VectorXd& s = svd.singularValues();
  Solved out;
  out.condition = s[r - 1] > 0 ? s[0] / s[r - 1] : std::numeric_limits<double>::infinity();
  if (!(s[r - 1] > options.excitation_tolerance * s[0])) {
    Eigen::Index worst = 0;
    svd.matrixV().col(r - 1).cwiseAbs().maxCoeff(&worst);
    char cond[32];
    std::snprintf(cond, sizeof cond, "%.3g", out.condition);
    throw IdentificationError(
        "the samples do not excite the base parameters: the base regressor's condition number is " +
        std::string(cond) + "; least seen: base parameter " +
        (static_cast<std::size_t>(worst) < names.size() ? names[static_cast<std::size_t>(worst)]
                                                          : std::to_string(worst)) +
        " (use more varied motion: every joint moving, with velocity and acceleration)");
  }
  out.theta = qr.solve(tw);
  out.residual = tw - Ww * out.theta;
  out.sigma = std::sqrt(out.residual.squaredNorm() / static_cast<double>(m - r));
  const Eigen::MatrixXd Rinv =
      R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(r, r));
  out.covariance = out.sigma * out.sigma * Rinv * Rinv.transpose();
  return out;
}

}  // namespace

Eigen::VectorXd jointWeights(const Eigen::VectorXd& joint_sigma) {
  const double largest = joint_sigma.size() > 0 ? joint_sigma.maxCoeff() : 0.0;
  if (!(largest > 0) || !std::isfinite(largest)) return Eigen::VectorXd::Ones(joint_sigma.size());
  return joint_sigma.cwiseMax(1e-9 * largest).cwiseInverse();
}

Eigen::VectorXd jointRms(const Eigen::VectorXd& residual, int nv) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(nv);
  const Eigen::Index n = nv > 0 ? residual.size() / nv : 0;
  for (Eigen::Index i = 0; i < n * nv; ++i) sum[i % nv] += residual[i] * residual[i];
  if (n == 0) return Eigen::VectorXd::Constant(nv, std::numeric_limits<double>::quiet_NaN());
  return (sum / static_cast<double>(n)).cwiseSqrt();
}

LeastSquaresFit solveLeastSquares(const Eigen::MatrixXd& W_base, const Eigen::VectorXd& tau, int nv,
                                  const LeastSquaresOptions& options, const std::vector<std::string>& base_names) {
  const Eigen::Index m = W_base.rows(), r = W_base.cols();
  if (tau.size() != m || nv <= 0 || m % nv != 0)
    throw IdentificationError("least squares: " + std::to_string(m) + " regressor rows for " +
                              std::to_string(tau.size()) + " torques (nv " + std::to_string(nv) + ")");
  if (r == 0) throw IdentificationError("least squares: no base parameters");
  if (m <= r)
    throw IdentificationError("least squares: " + std::to_string(m / nv) + " samples give " + std::to_string(m) +
                              " equations for " + std::to_string(r) + " base parameters; at least " +
                              std::to_string(r / nv + 1) + " samples are needed (many more for a useful fit)");
  Solved ols = fit(W_base, tau, nv, Eigen::VectorXd::Ones(nv), options, base_names);

  LeastSquaresFit out;
  out.degrees_of_freedom = static_cast<int>(m - r);
  // Each joint's noise from the OLS residuals, sharing out the degrees of freedom.
  const double dof_fraction = static_cast<double>(m - r) / static_cast<double>(m);
  out.joint_sigma = jointRms(ols.residual, nv) * std::sqrt(1.0 / dof_fraction);

  Solved chosen = std::move(ols);
  if (options.weighted) {
    out.weighted = true;
    const Eigen::VectorXd weights = jointWeights(out.joint_sigma);
    if (!weights.isOnes(0.0)) chosen = fit(W_base, tau, nv, weights, options, base_names);
  }
  out.theta = chosen.theta;
  out.covariance = chosen.covariance;
  out.sigma = chosen.sigma;
  out.condition_number = chosen.condition;
  out.std_errors = out.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  out.relative_std.resize(r);
  for (Eigen::Index i = 0; i < r; ++i)
    out.relative_std[i] = out.theta[i] != 0 ? 100.0 * out.std_errors[i] / std::abs(out.theta[i])
                                            : std::numeric_limits<double>::infinity();
  return out;
}

}  // namespace robodiff::batch
