#pragma once
// Ordinary and weighted least squares on the base regressor: tau = W_base theta + e.
//
// OLS: theta = argmin |tau - W_base theta|^2 by Householder QR of W_base (never the normal
// equations, which square the condition number); sigma^2 = |e|^2 / (m - r) (m rows, r base
// parameters); covariance sigma^2 (W_base^T W_base)^-1 = sigma^2 R^-1 R^-T; standard errors
// its diagonal's square roots; relative standard deviations 100 * se / |theta| (percent).
//
// WLS (iterated once): the OLS residuals give each joint's noise, sigma_j^2 = |e_j|^2 /
// (N (1 - r / m)) (the global degrees of freedom shared out over the joints); the rows of
// joint j are then weighted by 1 / sigma_j and the fit is redone. Covariance s^2 (W_w^T
// W_w)^-1 with s^2 the weighted residuals' variance (about 1 when the noise model holds).
// A joint with sigma_j = 0 (noise-free) is floored at 1e-9 * the largest sigma_j; when all
// are 0 the weights stay 1.
//
// Excitation: the samples must excite every base parameter. When the (weighted) base
// regressor's smallest singular value is below excitation_tolerance * its largest, the
// fit fails naming the base parameter least seen by the data.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace robodiff::batch {

struct LeastSquaresOptions {
  bool weighted = false;
  double excitation_tolerance = 1e-10;
};

struct LeastSquaresFit {
  bool weighted = false;
  Eigen::VectorXd theta;           // r base parameters
  Eigen::MatrixXd covariance;      // r x r
  Eigen::VectorXd std_errors;      // r
  Eigen::VectorXd relative_std;    // r, percent (infinity where theta is 0)
  Eigen::VectorXd joint_sigma;     // nv: each joint's noise estimated from the OLS residuals
  double sigma = 0;                // the residuals' standard deviation (WLS: of the weighted residuals)
  double condition_number = 0;     // of the (weighted) base regressor
  int degrees_of_freedom = 0;      // m - r
};

// `W_base` (N nv x r) and `tau` (N nv), rows of sample k at k*nv .. k*nv + nv - 1.
// `base_names` (optional, r) name the parameters in errors. Throws IdentificationError.
LeastSquaresFit solveLeastSquares(const Eigen::MatrixXd& W_base, const Eigen::VectorXd& tau, int nv,
                                  const LeastSquaresOptions& options = {},
                                  const std::vector<std::string>& base_names = {});

// The row weight of each joint, 1 / sigma_j, from each joint's noise: a joint with sigma_j = 0
// is floored at 1e-9 * the largest sigma_j; all 1 when every sigma_j is 0 (or not finite).
Eigen::VectorXd jointWeights(const Eigen::VectorXd& joint_sigma);

// Root mean square of `residual` per joint (rows of joint j at k*nv + j): nv values.
Eigen::VectorXd jointRms(const Eigen::VectorXd& residual, int nv);

}  // namespace robodiff::batch
