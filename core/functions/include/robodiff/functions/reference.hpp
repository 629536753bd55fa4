// The double-precision reference for a spec: core/dynamics evaluated directly, and
// central finite differences of it. What generated code is checked against (tests,
// `robodiff check`), independent of tracing, differentiation and code generation.
//
// Inputs are "all inputs": every input of the function in its order (q, v, a for rnea),
// fixed ones included; completeInputs() fills those in from the spec.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff {

// The function's inputs in order, the variable ones from `variable` (in order), the
// fixed ones from the spec.
std::vector<Eigen::VectorXd> completeInputs(const FunctionSpec& spec, const std::vector<Eigen::VectorXd>& variable);

// A random state for the variable inputs (q a valid configuration, v and a in [-1, 1],
// tau in [-5, 5]), and the Hessian weights in [-1, 1] if the function takes them.
// Same seed, same numbers.
std::vector<Eigen::VectorXd> randomRuntimeInputs(const Model& model, const FunctionSpec& spec, std::uint64_t seed);

// The value, flattened row-major.
Eigen::VectorXd referenceValue(const Model& model, const FunctionSpec& spec, const std::vector<Eigen::VectorXd>& all);

// Central differences of referenceValue w.r.t. the inputs `wrt` (q moved in the tangent
// space with integrate), value entries x tangent columns.
Eigen::MatrixXd finiteDifferenceJacobian(const Model& model, const FunctionSpec& spec,
                                         const std::vector<Eigen::VectorXd>& all, const std::vector<std::string>& wrt,
                                         double h = 1e-6);

// Second central differences of sum_i w_i value_i w.r.t. `wrt` (symmetric, n x n).
Eigen::MatrixXd finiteDifferenceHessian(const Model& model, const FunctionSpec& spec,
                                        const std::vector<Eigen::VectorXd>& all, const Eigen::VectorXd& weights,
                                        const std::vector<std::string>& wrt, double h = 1e-4);

}  // namespace robodiff
