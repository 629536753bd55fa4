#pragma once
// An identification result as JSON, for machines (`robodiff identify --json`):
//   robot, urdf, samples, method, fit_samples, held_out_samples,
//   base_parameters: [{name, expression, value, prior, std_error, relative_std_percent}],
//   base_mapping: {independent, dependent (standard indices), K (rows per base parameter)}
//     with base = pi[independent] + K pi[dependent],
//   bodies: [{joint, link, merged_links, parameters, prior, std_errors (objects keyed
//     m, mcx, ..., Izz), inertial {mass, com, inertia about the com}, physically_consistent,
//     consistency_problem, validity {principal_moments, triangle_margin,
//     pseudo_inertia_min_eigenvalue}}],
//   residual_rms: {joints, fit, held_out, prior_fit, prior_held_out} (N m or N per joint),
//   joint_sigma, sigma, condition_number, no_effect, warnings, times [{phase, seconds}],
//   ignored_columns; for the physically consistent fit also solver {solver, success,
//   cancelled, status, iterations, seconds, setup_seconds, regularization, weighting,
//   residual_rms, regularization_term, projected_prior_bodies}.
// Numbers that are not defined (NaN) are null.

#include <nlohmann/json.hpp>

#include "robodiff/batch/identification.hpp"

namespace robodiff::batch {

nlohmann::json identificationJson(const IdentificationProblem& problem, const IdentificationResult& result);

// Velocity labels of the model's joints: the joint's name, or name.vx ... for a free-flyer.
std::vector<std::string> jointLabels(const Model& model);

}  // namespace robodiff::batch
