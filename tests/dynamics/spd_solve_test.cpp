// Small symmetric positive-definite systems (core/dynamics/spd_inverse.hpp): the LDL^T
// solve that a floating base's root takes in ABA, and the Cholesky inverse every other
// multi-DoF joint takes, both against Eigen's own factorisations.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/spd_inverse.hpp"

namespace robodiff {
namespace {

// A x A^T + n 1: symmetric positive definite, condition number up to a few hundred.
JointSquare<double> randomSpd(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  JointSquare<double> a(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) a(i, j) = u(rng);
  return a * a.transpose() + 0.05 * n * JointSquare<double>::Identity(n, n);
}

TEST(SpdSolve, SolvesAsEigensLdltDoesForEverySizeOfAJoint) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int n = 1; n <= 6; ++n)
    for (int trial = 0; trial < 20; ++trial) {
      const JointSquare<double> a = randomSpd(n, rng);
      JointVector<double> b(n);
      for (int i = 0; i < n; ++i) b[i] = u(rng);
      const JointVector<double> x = solveSymmetricPositiveDefinite<double>(a, b);
      const JointVector<double> expected = a.ldlt().solve(b);
      EXPECT_LT((x - expected).norm(), 1e-11 * expected.norm()) << "n " << n << " trial " << trial;
      EXPECT_LT((a * x - b).norm(), 1e-12 * (a.norm() * x.norm() + b.norm())) << "n " << n;
    }
}

TEST(SpdSolve, TheInverseAgreesWithTheSolve) {
  std::mt19937 rng(6);
  const JointSquare<double> a = randomSpd(6, rng);
  const JointSquare<double> inverse = inverseSymmetricPositiveDefinite<double>(a);
  EXPECT_LT((inverse - a.llt().solve(JointSquare<double>::Identity(6, 6))).norm(), 1e-11 * inverse.norm());
  JointVector<double> b(6);
  b << 1, -2, 0.5, 3, -1, 0.25;
  EXPECT_LT((inverse * b - solveSymmetricPositiveDefinite<double>(a, b)).norm(), 1e-11 * (inverse * b).norm());
}

}  // namespace
}  // namespace robodiff
