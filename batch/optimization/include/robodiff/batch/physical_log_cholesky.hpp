#pragma once
// The log-Cholesky parametrisation of one rigid body's inertial parameters (Rucker &
// Wensing, "Smooth parameterization of rigid-body inertia", IEEE RA-L 2022): every
// theta in R^10 is a physically valid body, and every strictly valid body has exactly
// one theta.
//
// The body's pseudo-inertia (Wensing, Kim & Slotine, RA-L 2017)
//   J = [[Sigma, h], [h^T, m]],  Sigma = 0.5 tr(I) 1 - I,  h = m c
// (I the rotational inertia about the body frame's origin) is positive definite exactly
// when m > 0 and the inertia about the centre of mass is positive definite with strict
// triangle inequalities. Writing J = U U^T with
//   U = e^alpha [[e^d1, s12, s13, t1],
//                [0,    e^d2, s23, t2],
//                [0,    0,    e^d3, t3],
//                [0,    0,    0,    1 ]]
// makes J positive definite for any
//   theta = [alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3].
// Then m = e^(2 alpha), c = t (the centre of mass), and the mass distribution's
// covariance about the centre of mass is V V^T (V the upper left 3 x 3 of U / e^alpha).
//
// Parameters pi = [m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz], as
// Inertia::parameters() and the regressor (core/dynamics/regressor.hpp) order them.

#include <Eigen/Core>

namespace robodiff::batch {

template <class S> using BodyVector = Eigen::Matrix<S, 10, 1>;

// pi(theta), for double and for robodiff's symbolic scalar (traced for the derivatives).
template <class S> BodyVector<S> parametersFromLogCholesky(const BodyVector<S>& theta) {
  using std::exp;  // and symbolic::exp by argument-dependent lookup
  const S m = exp(S(2) * theta[0]);
  const S e1 = exp(theta[1]), e2 = exp(theta[2]), e3 = exp(theta[3]);
  const S &s12 = theta[4], &s23 = theta[5], &s13 = theta[6];
  const S &t1 = theta[7], &t2 = theta[8], &t3 = theta[9];
  // Sigma / m = V V^T + t t^T.
  const S a00 = e1 * e1 + s12 * s12 + s13 * s13 + t1 * t1;
  const S a01 = s12 * e2 + s13 * s23 + t1 * t2;
  const S a02 = s13 * e3 + t1 * t3;
  const S a11 = e2 * e2 + s23 * s23 + t2 * t2;
  const S a12 = s23 * e3 + t2 * t3;
  const S a22 = e3 * e3 + t3 * t3;
  // I = tr(Sigma) 1 - Sigma.
  BodyVector<S> pi;
  pi << m, m * t1, m * t2, m * t3, m * (a11 + a22), -(m * a01), m * (a00 + a22), -(m * a02), -(m * a12),
      m * (a00 + a11);
  return pi;
}

// theta(pi) for a strictly valid body (positive definite pseudo-inertia); throws
// std::invalid_argument naming what fails otherwise (see projectToStrictlyValid).
BodyVector<double> logCholeskyFromParameters(const BodyVector<double>& pi);

// The 4 x 4 pseudo-inertia J of a body's parameters.
Eigen::Matrix4d pseudoInertia(const BodyVector<double>& pi);

// A strictly valid body near pi, for a starting point: a mass of at least `min_mass`
// (> 0), the centre of mass kept (at the origin when the mass is not positive), and the
// covariance of the mass distribution about the centre of mass made positive definite by
// raising its eigenvalues to at least max(1e-6 of the largest, (0.1 mm)^2). Bodies already
// strictly valid (their log-Cholesky factor exists) come back unchanged; `changed` says
// whether the body was moved.
BodyVector<double> projectToStrictlyValid(const BodyVector<double>& pi, double min_mass, bool* changed = nullptr);

}  // namespace robodiff::batch
