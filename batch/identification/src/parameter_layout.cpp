// The standard parameter layout: names per parameter and the links behind each body.
#include "robodiff/batch/parameter_layout.hpp"

#include <algorithm>
#include <cmath>

#include "robodiff/batch/identification_error.hpp"
#include "robodiff/dynamics/regressor.hpp"

namespace robodiff::batch {

const char* const kParameterSymbols[kParametersPerBody] = {"m",   "mcx", "mcy", "mcz", "Ixx",
                                                           "Ixy", "Iyy", "Ixz", "Iyz", "Izz"};

ParameterLayout parameterLayout(const Model& model) {
  ParameterLayout layout;
  layout.bodies.resize(static_cast<std::size_t>(model.njoints()));
  for (int j = 0; j < model.njoints(); ++j) layout.bodies[static_cast<std::size_t>(j)].joint = model.joints[j].name;
  // The loader adds each moving joint's frame, then at once its child link's frame (placed
  // at the identity); every later Body frame of the same joint hangs from fixed joints.
  for (const Frame& f : model.frames) {
    if (f.type != FrameType::Body || f.parent_joint < 0) continue;
    IdentifiedBody& body = layout.bodies[static_cast<std::size_t>(f.parent_joint)];
    if (body.link.empty()) body.link = f.name;
    else body.merged_links.push_back(f.name);
  }
  for (IdentifiedBody& body : layout.bodies) {
    if (body.link.empty())
      throw IdentificationError("joint '" + body.joint + "' moves no link: the model is not from a URDF");
    for (const char* symbol : kParameterSymbols) layout.names.push_back(std::string(symbol) + "_" + body.link);
  }
  return layout;
}

Eigen::VectorXd modelParameters(const Model& model) { return inertialParameters(model); }

Eigen::VectorXd parameterScales(const Eigen::VectorXd& prior) {
  const Eigen::Index bodies = prior.size() / kParametersPerBody;
  Eigen::VectorXd scales(prior.size());
  double mass_sum = 0, inertia_sum = 0;
  int massive = 0;
  std::vector<bool> has_mass(static_cast<std::size_t>(bodies));
  for (Eigen::Index j = 0; j < bodies; ++j) {
    const auto p = prior.segment<kParametersPerBody>(kParametersPerBody * j);
    const double m = p[0];
    if (!(m > 0)) continue;
    // trace(I_c) = trace(I_o) - 2 m |c|^2 (parallel-axis theorem), c = mc / m.
    const double trace_c = p[4] + p[6] + p[9] - 2 * p.segment<3>(1).squaredNorm() / m;
    const double I = std::max(trace_c / 3, m * 1e-4), L = std::sqrt(I / m);
    scales.segment<kParametersPerBody>(kParametersPerBody * j) << m, m * L, m * L, m * L, I, I, I, I, I, I;
    has_mass[static_cast<std::size_t>(j)] = true;
    mass_sum += m;
    inertia_sum += I;
    ++massive;
  }
  const double m = massive ? mass_sum / massive : 1.0, I = massive ? inertia_sum / massive : 0.01;
  const double L = std::sqrt(I / m);
  for (Eigen::Index j = 0; j < bodies; ++j)
    if (!has_mass[static_cast<std::size_t>(j)])
      scales.segment<kParametersPerBody>(kParametersPerBody * j) << m, m * L, m * L, m * L, I, I, I, I, I, I;
  return scales;
}

}  // namespace robodiff::batch
