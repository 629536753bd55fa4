// The three-way check of a spec's function: comparisons, tolerances, references.
#include "robodiff/functions/spec_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/reference.hpp"

namespace robodiff {
namespace {

// Tolerances on the relative error (see SpecComparison). Functions that invert the mass
// matrix lose digits with its condition number; finite differences carry truncation and
// rounding errors of about h^2 and eps/h (h^2 and eps/h^2 for second differences).
// Compiled code may fuse a*b + c into one FMA (rounded once, -march=native), the
// interpreter rounds twice: the two agree to rounding, amplified like the values.
constexpr double kValueTolerance = 1e-10, kInvertingValueTolerance = 1e-9;
constexpr double kJacobianTolerance = 1e-5, kHessianTolerance = 1e-4;
constexpr double kBackendTolerance = 1e-11, kInvertingBackendTolerance = 1e-9;
// A user function may invert the mass matrix anywhere (aba, minv), so its values and
// backends are held to the inverting tolerances; its expressions are arbitrary, with
// larger higher-order terms in the differences' truncation error.
constexpr double kUserDerivativeTolerance = 1e-4, kUserHessianTolerance = 1e-3;

// Output k against its reference: what the reference is, and the tolerance.
SpecComparison referenceComparison(const FunctionSpec& spec, std::size_t k, const std::string& name) {
  if (spec.isUser()) {
    switch (spec.user->outputs[k].kind) {
      case UserOutputKind::Value: return {name, "double evaluation", kInvertingValueTolerance};
      case UserOutputKind::Hessian: return {name, "second finite differences", kUserHessianTolerance};
      default: return {name, "finite differences", kUserDerivativeTolerance};  // Jacobian, gradient, vjp
    }
  }
  const bool inverting = spec.function == ModelFunction::Aba || spec.function == ModelFunction::Minv;
  switch (spec.outputs[k].kind) {
    case OutputKind::Value:
      return {name, "reference (core/dynamics)", inverting ? kInvertingValueTolerance : kValueTolerance};
    case OutputKind::Jacobian: return {name, "finite differences", kJacobianTolerance};
    case OutputKind::Hessian: return {name, "second finite differences", kHessianTolerance};
  }
  return {name, "?", 0.0};
}

// Output k of the tested code against the interpreter.
SpecComparison backendComparison(const FunctionSpec& spec, const std::string& name) {
  const bool inverting =
      spec.isUser() || spec.function == ModelFunction::Aba || spec.function == ModelFunction::Minv;
  return {name, "interpreted", inverting ? kInvertingBackendTolerance : kBackendTolerance};
}

}  // namespace

void SpecComparison::add(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected, int state_index,
                         std::uint64_t state_seed) {
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols())
    throw std::logic_error("check: " + output + " is " + std::to_string(actual.rows()) + " x " +
                           std::to_string(actual.cols()) + ", expected " + std::to_string(expected.rows()) + " x " +
                           std::to_string(expected.cols()));
  const double floor = std::max(1e-6, 1e-3 * (expected.size() ? expected.cwiseAbs().maxCoeff() : 0.0));
  for (Eigen::Index r = 0; r < expected.rows(); ++r)
    for (Eigen::Index c = 0; c < expected.cols(); ++c) {
      double abs = std::abs(actual(r, c) - expected(r, c));
      if (std::isnan(abs)) abs = std::numeric_limits<double>::infinity();  // NaN fails
      const double rel = abs / std::max(std::abs(expected(r, c)), floor);
      worst_abs = std::max(worst_abs, abs);
      if (state < 0 || rel > worst_rel) worst_rel = rel, state = state_index, seed = state_seed, row = r, col = c;
    }
}

std::vector<Eigen::VectorXd> specAllInputs(const FunctionSpec& spec, const BuiltFunction& built,
                                           const std::vector<Eigen::VectorXd>& runtime) {
  std::vector<Eigen::VectorXd> variable;
  for (std::size_t b = 0; b < built.definition.inputs.size(); ++b)
    if (built.definition.inputs[b].name != "weights") variable.push_back(runtime.at(b));
  return completeInputs(spec, variable);
}

Eigen::VectorXd specHessianWeights(const FunctionSpec& spec, const BuiltFunction& built, std::size_t k,
                                   const std::vector<Eigen::VectorXd>& runtime) {
  const OutputSpec& o = spec.outputs.at(k);
  if (o.fixed_weights)
    return Eigen::Map<const Eigen::VectorXd>(o.fixed_weights->data(),
                                             static_cast<Eigen::Index>(o.fixed_weights->size()));
  for (std::size_t b = 0; b < built.definition.inputs.size(); ++b)
    if (built.definition.inputs[b].name == "weights") return runtime.at(b);
  throw std::logic_error("specHessianWeights: output " + std::to_string(k) + " takes no weights");
}

Eigen::MatrixXd specValueMatrix(const BuiltFunction& built, const Eigen::VectorXd& flat) {
  Eigen::MatrixXd m(built.value_rows, built.value_cols);
  for (Eigen::Index r = 0, i = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) m(r, c) = flat[i++];
  return m;
}

std::vector<Eigen::MatrixXd> specBlockMatrices(const FunctionSpec& spec, const BuiltFunction& built,
                                               const std::vector<Eigen::VectorXd>& blocks) {
  if (blocks.size() != built.definition.outputs.size())
    throw std::invalid_argument(built.definition.name + " has " + std::to_string(built.definition.outputs.size()) +
                                " output blocks, " + std::to_string(blocks.size()) + " given");
  std::vector<Eigen::MatrixXd> out;
  for (std::size_t k = 0; k < blocks.size(); ++k)
    out.push_back(blockMatrix(built.definition.outputs[k], blocks[k], spec.outputs[k].kind == OutputKind::Hessian));
  return out;
}

std::vector<Eigen::MatrixXd> specReferenceOutputs(const Model& model, const FunctionSpec& spec,
                                                  const BuiltFunction& built,
                                                  const std::vector<Eigen::VectorXd>& runtime) {
  const std::vector<Eigen::VectorXd> all = specAllInputs(spec, built, runtime);
  if (spec.isUser()) return userReferenceOutputs(model, spec, all);
  std::vector<Eigen::MatrixXd> out;
  for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
    const OutputSpec& o = spec.outputs[k];
    if (o.kind == OutputKind::Value) out.push_back(specValueMatrix(built, referenceValue(model, spec, all)));
    else if (o.kind == OutputKind::Jacobian) out.push_back(finiteDifferenceJacobian(model, spec, all, o.wrt));
    else out.push_back(finiteDifferenceHessian(model, spec, all, specHessianWeights(spec, built, k, runtime), o.wrt));
  }
  return out;
}

std::vector<SpecComparison> checkSpecFunction(const Model& model, const FunctionSpec& spec, const BuiltFunction& built,
                                              const BlockEvaluator& tested, const BlockEvaluator& interpreted,
                                              const SpecCheckOptions& options) {
  const std::size_t n = spec.outputs.size();
  const bool against_interpreter = static_cast<bool>(interpreted);
  std::vector<SpecComparison> rows;  // per output: against the reference, then the interpreter
  for (std::size_t k = 0; k < n; ++k) {
    const std::string& name = built.outputs[k].name;
    rows.push_back(referenceComparison(spec, k, name));
    if (against_interpreter) rows.push_back(backendComparison(spec, name));
  }
  const std::size_t per_output = against_interpreter ? 2 : 1;
  for (int s = 0; s < options.samples; ++s) {
    const std::uint64_t seed = options.seed + static_cast<std::uint64_t>(s);
    const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, spec, seed);
    const std::vector<Eigen::MatrixXd> got = tested(runtime);
    const std::vector<Eigen::MatrixXd> expected = specReferenceOutputs(model, spec, built, runtime);
    std::vector<Eigen::MatrixXd> other;
    if (against_interpreter) other = interpreted(runtime);
    for (std::size_t k = 0; k < n; ++k) {
      rows[k * per_output].add(got.at(k), expected.at(k), s, seed);
      if (against_interpreter) rows[k * per_output + 1].add(got.at(k), other.at(k), s, seed);
    }
  }
  return rows;
}

}  // namespace robodiff
