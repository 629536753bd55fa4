// The inverse of the log-Cholesky map, the pseudo-inertia, and the projection of a body
// that is not strictly valid (a massless link, a flat inertia) into the valid set.
#include "robodiff/batch/physical_log_cholesky.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace robodiff::batch {
namespace {

Eigen::Matrix3d rotationalInertia(const BodyVector<double>& pi) {
  Eigen::Matrix3d inertia;
  inertia << pi[4], pi[5], pi[7],
             pi[5], pi[6], pi[8],
             pi[7], pi[8], pi[9];
  return inertia;
}

// Sigma = 0.5 tr(I) 1 - I: the second moment of the mass distribution about the origin.
Eigen::Matrix3d secondMoment(const BodyVector<double>& pi) {
  const Eigen::Matrix3d inertia = rotationalInertia(pi);
  return 0.5 * inertia.trace() * Eigen::Matrix3d::Identity() - inertia;
}

// The body of mass m, centre of mass c and mass covariance `covariance` about c.
BodyVector<double> bodyFrom(double m, const Eigen::Vector3d& c, const Eigen::Matrix3d& covariance) {
  const Eigen::Matrix3d sigma = m * (covariance + c * c.transpose());
  const Eigen::Matrix3d inertia = sigma.trace() * Eigen::Matrix3d::Identity() - sigma;
  BodyVector<double> pi;
  pi << m, m * c.x(), m * c.y(), m * c.z(), inertia(0, 0), inertia(0, 1), inertia(1, 1), inertia(0, 2),
      inertia(1, 2), inertia(2, 2);
  return pi;
}

}  // namespace

Eigen::Matrix4d pseudoInertia(const BodyVector<double>& pi) {
  Eigen::Matrix4d j;
  j.topLeftCorner<3, 3>() = secondMoment(pi);
  j.topRightCorner<3, 1>() = pi.segment<3>(1);
  j.bottomLeftCorner<1, 3>() = pi.segment<3>(1).transpose();
  j(3, 3) = pi[0];
  return j;
}

BodyVector<double> logCholeskyFromParameters(const BodyVector<double>& pi) {
  if (!pi.allFinite()) throw std::invalid_argument("log-Cholesky: the parameters are not all finite");
  const double m = pi[0];
  if (!(m > 0)) throw std::invalid_argument("log-Cholesky: the mass " + std::to_string(m) + " kg is not positive");
  const Eigen::Vector3d c = pi.segment<3>(1) / m;
  Eigen::Matrix3d covariance = secondMoment(pi) / m - c * c.transpose();
  covariance = 0.5 * (covariance + covariance.transpose()).eval();
  // V V^T = covariance with V upper triangular: the Cholesky factor of the matrix with
  // rows and columns reversed, reversed back (P L P is upper triangular for the exchange P).
  const Eigen::Matrix3d reversed = covariance.reverse();
  const Eigen::LLT<Eigen::Matrix3d> llt(reversed);
  const Eigen::Matrix3d lower = llt.matrixL();
  const Eigen::Matrix3d v = lower.reverse();
  if (llt.info() != Eigen::Success || !(v.diagonal().array() > 0).all() || !v.allFinite())
    throw std::invalid_argument(
        "log-Cholesky: the mass distribution about the centre of mass is not positive definite (a rotational "
        "inertia about the centre of mass with a non-positive moment or a triangle inequality not strict)");
  BodyVector<double> theta;
  theta << 0.5 * std::log(m), std::log(v(0, 0)), std::log(v(1, 1)), std::log(v(2, 2)), v(0, 1), v(1, 2), v(0, 2),
      c.x(), c.y(), c.z();
  return theta;
}

BodyVector<double> projectToStrictlyValid(const BodyVector<double>& pi, double min_mass, bool* changed) {
  if (!(min_mass > 0)) throw std::invalid_argument("projectToStrictlyValid: min_mass must be positive");
  if (!pi.allFinite()) throw std::invalid_argument("projectToStrictlyValid: the parameters are not all finite");
  if (changed != nullptr) *changed = false;
  try {
    const BodyVector<double> theta = logCholeskyFromParameters(pi);
    if (theta.allFinite()) return pi;
  } catch (const std::invalid_argument&) {
    // not strictly valid: projected below
  }
  if (changed != nullptr) *changed = true;
  const double m = pi[0];
  const double mass = std::max(m, min_mass);
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  if (m > 0) {
    c = pi.segment<3>(1) / m;
    covariance = secondMoment(pi) / m - c * c.transpose();
    covariance = 0.5 * (covariance + covariance.transpose()).eval();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance);
  Eigen::Vector3d values = eig.eigenvalues();
  const double floor = std::max(1e-6 * std::max(values.maxCoeff(), 0.0), 1e-8);  // (0.1 mm)^2
  values = values.cwiseMax(floor);
  const Eigen::Matrix3d projected = eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
  return bodyFrom(mass, c, 0.5 * (projected + projected.transpose()));
}

}  // namespace robodiff::batch
