// The validity check of inertial parameters: mass, the inertia about the centre of mass
// (moments, triangle inequalities) and the pseudo-inertia's smallest eigenvalue.
#include "robodiff/batch/physical_validity.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "robodiff/batch/physical_log_cholesky.hpp"

namespace robodiff::batch {

BodyValidity checkBodyValidity(const Eigen::Ref<const Eigen::VectorXd>& body, double tolerance) {
  if (body.size() != 10)
    throw std::invalid_argument("checkBodyValidity: a body has 10 parameters, not " + std::to_string(body.size()));
  if (!(tolerance >= 0)) throw std::invalid_argument("checkBodyValidity: the tolerance must be >= 0");
  const BodyVector<double> pi = body;
  BodyValidity v;
  v.mass = pi[0];
  std::ostringstream why;
  auto reason = [&](const std::string& text) { why << (why.tellp() > 0 ? "; " : "") << text; };
  if (!pi.allFinite()) {
    v.principal_moments.setConstant(std::nan(""));
    v.triangle_margin = v.pseudo_inertia_min_eigenvalue = std::nan("");
    v.message = "parameters are not all finite";
    return v;
  }

  // The inertia about the centre of mass (parallel axis theorem); about the origin when
  // the mass is zero (no centre of mass).
  Eigen::Matrix3d inertia;
  inertia << pi[4], pi[5], pi[7],
             pi[5], pi[6], pi[8],
             pi[7], pi[8], pi[9];
  if (pi[0] != 0) {
    const Eigen::Vector3d c = pi.segment<3>(1) / pi[0];
    inertia -= pi[0] * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  }
  v.principal_moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertia, Eigen::EigenvaluesOnly).eigenvalues();
  const Eigen::Vector3d& moments = v.principal_moments;
  v.triangle_margin = moments.sum() - 2 * moments.maxCoeff();  // the largest moment decides
  // Dynamic size: GCC 12 warns (spuriously) inside Eigen's unrolled AVX-512 code for a fixed 4 x 4.
  v.pseudo_inertia_min_eigenvalue =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(pseudoInertia(pi)), Eigen::EigenvaluesOnly)
          .eigenvalues()[0];

  if (!(pi[0] > 0)) reason("mass " + std::to_string(pi[0]) + " kg is not positive");
  if (moments[0] < -tolerance || (tolerance == 0 && moments[0] <= 0)) {
    std::ostringstream m;
    m << "the rotational inertia about the centre of mass is not positive definite (principal moments "
      << moments.transpose() << " kg m^2)";
    reason(m.str());
  }
  if (v.triangle_margin < -tolerance) {
    std::ostringstream m;
    m << "the triangle inequality fails: the largest principal moment " << moments[2] << " exceeds the sum "
      << moments[0] + moments[1] << " of the other two";
    reason(m.str());
  }
  v.message = why.str();
  v.valid = v.message.empty();
  return v;
}

std::vector<BodyValidity> checkValidity(const Eigen::Ref<const Eigen::VectorXd>& parameters, double tolerance) {
  if (parameters.size() % 10 != 0)
    throw std::invalid_argument("checkValidity: " + std::to_string(parameters.size()) +
                                " parameters is not 10 per body");
  std::vector<BodyValidity> out;
  for (Eigen::Index b = 0; b < parameters.size() / 10; ++b)
    out.push_back(checkBodyValidity(parameters.segment(10 * b, 10), tolerance));
  return out;
}

bool allValid(const std::vector<BodyValidity>& bodies) {
  return std::all_of(bodies.begin(), bodies.end(), [](const BodyValidity& b) { return b.valid; });
}

std::string describeInvalid(const std::vector<BodyValidity>& bodies) {
  std::ostringstream out;
  for (std::size_t b = 0; b < bodies.size(); ++b)
    if (!bodies[b].valid) out << "body " << b << ": " << bodies[b].message << "\n";
  return out.str();
}

}  // namespace robodiff::batch
