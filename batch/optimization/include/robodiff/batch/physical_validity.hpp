#pragma once
// Physical validity of identified inertial parameters, body by body: a positive mass, a
// positive definite rotational inertia about the centre of mass, and its principal
// moments satisfying the triangle inequalities (each at most the sum of the other two).
// Together these say the parameters belong to some real mass distribution; they are
// equivalent to a positive semidefinite pseudo-inertia (Wensing, Kim & Slotine 2017),
// whose smallest eigenvalue is reported too.
//
// Parameters per body: [m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz], the
// rotational inertia about the body frame's origin (Inertia::parameters()).

#include <string>
#include <vector>

#include <Eigen/Core>

namespace robodiff::batch {

struct BodyValidity {
  bool valid = false;
  double mass = 0;                                          // kg
  Eigen::Vector3d principal_moments = Eigen::Vector3d::Zero();  // about the centre of mass, ascending, kg m^2
  // min over the principal moments of (sum of the other two - this one); >= 0 when valid.
  double triangle_margin = 0;
  double pseudo_inertia_min_eigenvalue = 0;                 // of the 4 x 4 pseudo-inertia
  std::string message;  // what fails, readable; empty when valid
};

// One body: 10 parameters (throws std::invalid_argument for another size). `tolerance`
// (kg m^2, >= 0) lets moments and triangle margins down to -tolerance count as valid
// (rounding of parameters that lie on the boundary); the mass must be positive.
BodyValidity checkBodyValidity(const Eigen::Ref<const Eigen::VectorXd>& body, double tolerance = 0);

// Every body of a parameter vector (10 per body; throws std::invalid_argument when the
// size is not a multiple of 10).
std::vector<BodyValidity> checkValidity(const Eigen::Ref<const Eigen::VectorXd>& parameters, double tolerance = 0);

bool allValid(const std::vector<BodyValidity>& bodies);

// "body 3: mass -0.2 kg is not positive; ..." for each invalid body, one per line;
// empty when all are valid.
std::string describeInvalid(const std::vector<BodyValidity>& bodies);

}  // namespace robodiff::batch
