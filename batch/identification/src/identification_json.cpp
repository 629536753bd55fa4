// The identification result as JSON.
#include "robodiff/batch/identification_json.hpp"

#include <cmath>

#include "robodiff/batch/urdf_inertials.hpp"

namespace robodiff::batch {
namespace {

nlohmann::json number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

nlohmann::json vector(const Eigen::VectorXd& v) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(number(v[i]));
  return out;
}

nlohmann::json keyed(const Eigen::Matrix<double, 10, 1>& p) {
  nlohmann::json out = nlohmann::json::object();
  for (int i = 0; i < kParametersPerBody; ++i) out[kParameterSymbols[i]] = number(p[i]);
  return out;
}

}  // namespace

std::vector<std::string> jointLabels(const Model& model) {
  static const char* ff[] = {".vx", ".vy", ".vz", ".wx", ".wy", ".wz"};
  std::vector<std::string> labels;
  for (const Joint& j : model.joints)
    for (int k = 0; k < j.nv; ++k)
      labels.push_back(j.nv == 1 ? j.name : j.type == JointType::FreeFlyer ? j.name + ff[k] : j.name + "." + std::to_string(k));
  return labels;
}

nlohmann::json identificationJson(const IdentificationProblem& problem, const IdentificationResult& result) {
  const BaseParameters& base = problem.base;
  nlohmann::json out;
  out["robot"] = problem.model.name;
  out["urdf"] = problem.urdf_source;
  out["floating_base"] = problem.floating_base;
  out["samples"] = problem.samples_source;
  out["method"] = result.method;
  out["fit_samples"] = problem.fit.samples();
  out["held_out_samples"] = problem.held_out.samples();
  out["standard_parameters"] = problem.layout.names;

  nlohmann::json params = nlohmann::json::array();
  for (int k = 0; k < base.size(); ++k)
    params.push_back({{"name", base.name(k, problem.layout)},
                      {"expression", base.describe(k, problem.layout)},
                      {"value", number(result.base_values[k])},
                      {"prior", number(result.base_prior[k])},
                      {"std_error", number(result.base_std_errors[k])},
                      {"relative_std_percent", number(result.base_relative_std[k])}});
  out["base_parameters"] = params;
  nlohmann::json K = nlohmann::json::array();
  for (Eigen::Index i = 0; i < base.K.rows(); ++i) K.push_back(vector(base.K.row(i).transpose()));
  out["base_mapping"] = {{"independent", base.independent}, {"dependent", base.dependent}, {"K", K},
                         {"rank_tolerance", base.tolerance}, {"smallest_kept", base.smallest_kept},
                         {"largest_dropped", base.largest_dropped}};
  nlohmann::json no_effect = nlohmann::json::array();
  for (int i : base.no_effect) no_effect.push_back(problem.layout.names[static_cast<std::size_t>(i)]);
  out["no_effect"] = no_effect;

  nlohmann::json bodies = nlohmann::json::array();
  for (std::size_t j = 0; j < result.bodies.size(); ++j) {
    const BodyResult& b = result.bodies[j];
    const IdentifiedBody& layout = problem.layout.bodies[j];
    const BodyInertial inertial = inertialFromParameters(b.parameters);
    nlohmann::json I = nlohmann::json::array();
    for (int r = 0; r < 3; ++r) I.push_back(vector(inertial.inertia.row(r).transpose()));
    bodies.push_back({{"joint", layout.joint},
                      {"link", layout.link},
                      {"merged_links", layout.merged_links},
                      {"parameters", keyed(b.parameters)},
                      {"prior", keyed(b.prior)},
                      {"std_errors", keyed(b.std_errors)},
                      {"inertial", {{"mass", number(inertial.mass)}, {"com", vector(inertial.com)}, {"inertia", I}}},
                      {"physically_consistent", b.validity.valid},
                      {"consistency_problem", b.validity.message},
                      {"validity", {{"principal_moments", vector(b.validity.principal_moments)},
                                    {"triangle_margin", number(b.validity.triangle_margin)},
                                    {"pseudo_inertia_min_eigenvalue",
                                     number(b.validity.pseudo_inertia_min_eigenvalue)}}}});
  }
  out["bodies"] = bodies;
  out["residual_rms"] = {{"joints", jointLabels(problem.model)},
                         {"fit", vector(result.rms_fit)},
                         {"held_out", vector(result.rms_held_out)},
                         {"prior_fit", vector(result.rms_prior_fit)},
                         {"prior_held_out", vector(result.rms_prior_held_out)}};
  out["joint_sigma"] = vector(result.joint_sigma);
  out["sigma"] = number(result.sigma);
  out["condition_number"] = number(result.condition_number);
  if (const std::optional<SolverReport>& s = result.solver)
    out["solver"] = {{"solver", s->solver},
                     {"success", s->success},
                     {"cancelled", s->cancelled},
                     {"status", s->status},
                     {"iterations", s->iterations},
                     {"seconds", number(s->seconds)},
                     {"setup_seconds", number(s->setup_seconds)},
                     {"regularization", number(s->regularization)},
                     {"weighting", s->weighting},
                     {"residual_rms", number(s->residual_rms)},
                     {"regularization_term", number(s->regularization_term)},
                     {"projected_prior_bodies", s->projected_prior_bodies}};
  out["warnings"] = result.warnings;
  nlohmann::json times = nlohmann::json::array();
  for (const PhaseTime& t : result.times) times.push_back({{"phase", t.phase}, {"seconds", t.seconds}});
  out["times"] = times;
  out["ignored_columns"] = problem.ignored_columns;
  return out;
}

}  // namespace robodiff::batch
