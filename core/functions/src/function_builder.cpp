#include "robodiff/functions/function_builder.hpp"

#include <algorithm>
#include <optional>

#include "robodiff/symbolic/cone.hpp"
#include "model_function_build.hpp"
#include "user_function_builder.hpp"

namespace robodiff {

using symbolic::NodeId;

std::size_t builtOperations(const BuiltFunction& f) {
  std::vector<NodeId> outputs;
  for (const codegen::OutputBlock& b : f.definition.outputs) outputs.insert(outputs.end(), b.values.begin(), b.values.end());
  return symbolic::coneSize(*f.graph, outputs).operations;
}

BuiltFunction buildFunction(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options) {
  if (spec.user) return detail::buildUserFunction(model, spec, options);
  const bool rnea_jacobian = spec.function == ModelFunction::Rnea &&
                             std::any_of(spec.outputs.begin(), spec.outputs.end(),
                                         [](const OutputSpec& o) { return o.kind == OutputKind::Jacobian; });
  if (options.rnea_jacobian != RneaJacobianMethod::Cheaper || !rnea_jacobian) {
    FunctionBuilderOptions one = options;
    if (one.rnea_jacobian == RneaJacobianMethod::Cheaper) one.rnea_jacobian = RneaJacobianMethod::Differentiate;
    return detail::buildModelFunction(model, spec, one);
  }
  // Both ways (tracing takes milliseconds); a graph past the node limit on one way leaves
  // the other.
  FunctionBuilderOptions analytic = options, differentiated = options;
  analytic.rnea_jacobian = RneaJacobianMethod::Analytic;
  differentiated.rnea_jacobian = RneaJacobianMethod::Differentiate;
  std::optional<BuiltFunction> a, d;
  try {
    a = detail::buildModelFunction(model, spec, analytic);
  } catch (const symbolic::GraphTooLarge&) {
  }
  try {
    d = detail::buildModelFunction(model, spec, differentiated);
  } catch (const symbolic::GraphTooLarge&) {
    if (!a) throw;
  }
  if (!a) return std::move(*d);
  if (!d) return std::move(*a);
  const std::size_t a_ops = builtOperations(*a), d_ops = builtOperations(*d);
  const bool analytic_kept = static_cast<double>(a_ops) <= kAnalyticRneaOperationsRatio * static_cast<double>(d_ops);
  BuiltFunction& kept = analytic_kept ? *a : *d;
  const BuiltFunction& other = analytic_kept ? *d : *a;
  kept.method += "; chosen over " + std::string(analytic_kept ? "differentiation" : "the analytic derivatives") + " (" +
                 std::to_string(analytic_kept ? a_ops : d_ops) + " operations against " +
                 std::to_string(analytic_kept ? d_ops : a_ops) + ")";
  kept.timings.trace_seconds += other.timings.trace_seconds;
  kept.timings.differentiate_seconds += other.timings.differentiate_seconds;
  kept.timings.assemble_seconds += other.timings.assemble_seconds;
  return std::move(kept);
}

}  // namespace robodiff
