#include "robodiff/functions/function_builder.hpp"

#include <algorithm>
#include <optional>

#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/functions/function_library.hpp"
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

std::size_t builtInstructions(const BuiltFunction& f) {
  return codegen::singleKnotInstructions(*f.graph, f.definition, LibraryOptions::defaultCodegenOptions());
}

namespace {

bool hasOutput(const FunctionSpec& spec, OutputKind kind) {
  return std::any_of(spec.outputs.begin(), spec.outputs.end(), [&](const OutputSpec& o) { return o.kind == kind; });
}

// Whether every output is a value (no Jacobian, gradient, Hessian or product).
bool valuesOnly(const FunctionSpec& spec) {
  if (spec.user)
    return std::all_of(spec.user->outputs.begin(), spec.user->outputs.end(),
                       [](const UserOutput& o) { return o.kind == UserOutputKind::Value; });
  return !hasOutput(spec, OutputKind::Jacobian) && !hasOutput(spec, OutputKind::Hessian);
}

// Lane pairs seeded at a Jacobian's columns made derivative functions slower (Panda
// RNEA + J 1.22 -> 1.44 us); at twins, faster (docs/code-generation.md).
codegen::LanePairSeeds laneSeeds(const FunctionSpec& spec) {
  return valuesOnly(spec) ? codegen::LanePairSeeds::TwinsAndColumns : codegen::LanePairSeeds::Twins;
}

// One way of building a function, and how the method names it when the other is kept.
struct Way {
  FunctionBuilderOptions options;
  const char* name;
};

// What two ways are compared by: the operations of the function, or the instructions of
// its single-knot code (builtInstructions: the lane pairs counted).
enum class Cost { Operations, Instructions };

// Builds `spec` both ways (tracing takes milliseconds) and keeps the first where it costs
// at most `ratio` of the second, else the second; a graph past the node limit on one way
// leaves the other.
BuiltFunction cheaperOf(const Model& model, const FunctionSpec& spec, const Way& first, const Way& second,
                        double ratio, Cost cost) {
  auto build = [&](const FunctionBuilderOptions& o) {
    BuiltFunction built =
        spec.user ? detail::buildUserFunction(model, spec, o) : detail::buildModelFunction(model, spec, o);
    built.definition.lane_pairs = laneSeeds(spec);
    return built;
  };
  std::optional<BuiltFunction> a, b;
  try {
    a = build(first.options);
  } catch (const symbolic::GraphTooLarge&) {
  }
  try {
    b = build(second.options);
  } catch (const symbolic::GraphTooLarge&) {
    if (!a) throw;
  }
  if (!a) return std::move(*b);
  if (!b) return std::move(*a);
  const auto measure = cost == Cost::Operations ? builtOperations : builtInstructions;
  const std::size_t a_cost = measure(*a), b_cost = measure(*b);
  const bool first_kept = static_cast<double>(a_cost) <= ratio * static_cast<double>(b_cost);
  BuiltFunction& kept = first_kept ? *a : *b;
  const BuiltFunction& other = first_kept ? *b : *a;
  kept.method += "; chosen over " + std::string(first_kept ? second.name : first.name) + " (" +
                 std::to_string(first_kept ? a_cost : b_cost) +
                 (cost == Cost::Operations ? " operations against " : " single-knot instructions against ") +
                 std::to_string(first_kept ? b_cost : a_cost) + ")";
  kept.timings.trace_seconds += other.timings.trace_seconds;
  kept.timings.differentiate_seconds += other.timings.differentiate_seconds;
  kept.timings.assemble_seconds += other.timings.assemble_seconds;
  return std::move(kept);
}

// ABA's value where no Jacobian comes with it, in a model function or in a user function
// with value outputs only (with derivatives, `aba` takes its value from their sweep).
bool abaValueOnly(const FunctionSpec& spec) {
  if (spec.user) return detail::callsPrimitive(*spec.user, "aba") && valuesOnly(spec);
  return spec.function == ModelFunction::Aba && valuesOnly(spec);
}

BuiltFunction buildEitherWay(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options) {
  FunctionBuilderOptions one = options;
  if (one.rnea_jacobian == RneaJacobianMethod::Cheaper) one.rnea_jacobian = RneaJacobianMethod::Differentiate;
  if (one.aba_value == AbaValueMethod::Cheaper) one.aba_value = AbaValueMethod::Articulated;
  if (options.aba_value == AbaValueMethod::Cheaper && abaValueOnly(spec)) {
    Way factors{one, "M^-1 (tau - nle) by the factors"}, articulated{one, "ABA"};
    factors.options.aba_value = AbaValueMethod::Factors;
    return cheaperOf(model, spec, factors, articulated, 1.0, Cost::Operations);
  }
  if (spec.user) return detail::buildUserFunction(model, spec, one);
  const bool rnea_jacobian = spec.function == ModelFunction::Rnea && hasOutput(spec, OutputKind::Jacobian);
  if (options.rnea_jacobian == RneaJacobianMethod::Cheaper && rnea_jacobian) {
    Way analytic{one, "the analytic derivatives"}, differentiated{one, "differentiation"};
    analytic.options.rnea_jacobian = RneaJacobianMethod::Analytic;
    return cheaperOf(model, spec, analytic, differentiated, kAnalyticRneaInstructionsRatio, Cost::Instructions);
  }
  return detail::buildModelFunction(model, spec, one);
}

}  // namespace

BuiltFunction buildFunction(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options) {
  BuiltFunction built = buildEitherWay(model, spec, options);
  built.definition.lane_pairs = laneSeeds(spec);
  return built;
}

}  // namespace robodiff
