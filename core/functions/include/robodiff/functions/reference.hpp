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

// User functions (spec.user): the double evaluation of the same expressions
// (user_evaluator.hpp on double) and central finite differences of it, output by output,
// in the layout of the built blocks as matrices: a value rows x cols, a Jacobian value
// entries (a configuration's: nv tangent entries) x tangent columns, a gradient and a
// vector-Jacobian product n x 1, a Hessian the full n x n matrix. Configurations are
// moved with integrate, and a configuration-valued expression is compared by its
// difference in the tangent space.
std::vector<Eigen::MatrixXd> userReferenceOutputs(const Model& model, const FunctionSpec& spec,
                                                  const std::vector<Eigen::VectorXd>& all, double h_jacobian = 1e-6,
                                                  double h_hessian = 1e-4);

// The value of output k's expression at `all` (flattened row-major; a configuration's
// coordinates), and whether it is a configuration.
Eigen::VectorXd userReferenceValue(const Model& model, const FunctionSpec& spec, std::size_t output,
                                   const std::vector<Eigen::VectorXd>& all, bool* configuration = nullptr);

}  // namespace robodiff
