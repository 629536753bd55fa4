#pragma once
// The layout of the standard inertial parameter vector pi the regressor multiplies
// (core/dynamics/regressor.hpp): 10 per moving joint, in joint order, for the composite
// body the joint moves, about the joint frame's origin, in the joint frame:
//   [m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]     (mc = m * centre of mass)
// Each body is named after its carrier link: the URDF link whose frame is the joint frame
// (the joint's child link). Links attached to it by fixed joints are merged into the same
// composite body; they are listed as the body's merged links.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/model/model.hpp"

namespace robodiff::batch {

inline constexpr int kParametersPerBody = 10;
// "m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz".
extern const char* const kParameterSymbols[kParametersPerBody];

struct IdentifiedBody {
  std::string joint;                      // the moving joint
  std::string link;                       // its carrier link (the joint's child link)
  std::vector<std::string> merged_links;  // links fixed to it, merged into the composite body
};

struct ParameterLayout {
  std::vector<IdentifiedBody> bodies;  // one per joint, in joint order
  std::vector<std::string> names;      // per parameter: "m_link3", "Izz_link7", ...

  int size() const { return static_cast<int>(names.size()); }
};

ParameterLayout parameterLayout(const Model& model);

// The standard parameters of the model's bodies (core/dynamics' inertialParameters).
Eigen::VectorXd modelParameters(const Model& model);

// The size of each standard parameter in `prior` (10 per body), for scaling: per body,
// mass m, inertias I = the mean principal moment about the centre of mass (trace(I_c) / 3,
// at least m * 1 cm^2), first moments m L with L = sqrt(I / m). Scales about the centre of
// mass keep small links' inertias from absorbing corrections that belong to masses and
// lever arms. A massless body takes the mean scales of the others (or 1 kg and 0.01 kg m^2).
Eigen::VectorXd parameterScales(const Eigen::VectorXd& prior);

}  // namespace robodiff::batch
