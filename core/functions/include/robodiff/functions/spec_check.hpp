// The three-way check of a spec's function (`robodiff check`, robodiff.check in Python):
// at seeded random states, every output block of the function under test is compared
// with what shares none of its code (the value with core/dynamics in double, a user
// function's with the double evaluation of its expressions; derivatives with central
// finite differences of that) and, optionally, with the interpreter (generated code
// against the builder's graph run node by node).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff {

// One output block against one expectation over all states: the worst absolute and
// relative error and where the relative one is. Relative errors are elementwise,
// relative to max(|expected|, 1e-3 max|expected|, 1e-6) (as tests/support/golden.cpp's
// matricesAgree), so entries near zero are not judged on noise. NaN counts as infinite.
struct SpecComparison {
  std::string output, against;
  double tolerance = 0;
  double worst_abs = 0, worst_rel = 0;
  int state = -1;  // index of the state with the worst relative error
  std::uint64_t seed = 0;
  Eigen::Index row = 0, col = 0;

  bool pass() const { return worst_rel <= tolerance; }
  // Folds one state's block in; throws std::logic_error when the shapes differ.
  void add(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected, int state_index, std::uint64_t state_seed);
};

// A function's output blocks at the runtime inputs (one vector per input block of the
// built definition), as specBlockMatrices gives them.
using BlockEvaluator = std::function<std::vector<Eigen::MatrixXd>(const std::vector<Eigen::VectorXd>& runtime)>;

// All inputs of the function (fixed ones from the spec) from the runtime blocks.
std::vector<Eigen::VectorXd> specAllInputs(const FunctionSpec& spec, const BuiltFunction& built,
                                           const std::vector<Eigen::VectorXd>& runtime);
// The weights of output `k` (a Hessian): fixed in the spec or the runtime block.
Eigen::VectorXd specHessianWeights(const FunctionSpec& spec, const BuiltFunction& built, std::size_t k,
                                   const std::vector<Eigen::VectorXd>& runtime);
// The value, flattened row-major, as a rows x cols matrix.
Eigen::MatrixXd specValueMatrix(const BuiltFunction& built, const Eigen::VectorXd& flat);
// Each output block's doubles (as the generated code writes them) as a matrix: the value
// rows x cols, Jacobians m x n, Hessians full and symmetric.
std::vector<Eigen::MatrixXd> specBlockMatrices(const FunctionSpec& spec, const BuiltFunction& built,
                                               const std::vector<Eigen::VectorXd>& blocks);

// Every output's reference at the runtime inputs, in the layout of specBlockMatrices.
std::vector<Eigen::MatrixXd> specReferenceOutputs(const Model& model, const FunctionSpec& spec,
                                                  const BuiltFunction& built,
                                                  const std::vector<Eigen::VectorXd>& runtime);

struct SpecCheckOptions {
  int samples = 10;        // random states (randomRuntimeInputs)
  std::uint64_t seed = 1;  // state i uses seed + i
};

// Checks `tested` at options.samples random states. Rows, per output in order: against
// the reference, then against `interpreted` when it is set. Tolerances: values 1e-10
// (1e-9 for aba, minv and user functions, which may invert the mass matrix), Jacobians
// 1e-5 (user functions 1e-4), Hessians 1e-4 (1e-3), backends 1e-11 (1e-9).
std::vector<SpecComparison> checkSpecFunction(const Model& model, const FunctionSpec& spec, const BuiltFunction& built,
                                              const BlockEvaluator& tested, const BlockEvaluator& interpreted,
                                              const SpecCheckOptions& options);

}  // namespace robodiff
