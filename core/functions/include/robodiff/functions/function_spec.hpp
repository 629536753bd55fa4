// A function spec: which model function to build, which of its inputs are variables
// (given at each evaluation) and which are fixed (folded into the generated code),
// which outputs (value, Jacobians, weighted Hessians), and how to build it.
// The JSON form is described by schema/function-spec.schema.json; examples/specs/
// holds a documented spec for each function.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "robodiff/dynamics/jacobian.hpp"
#include "robodiff/functions/user_function.hpp"

namespace robodiff {

enum class ModelFunction { Rnea, Aba, Crba, Gravity, Nle, Fk, FrameJacobian, Com, Regressor, Minv };

struct FunctionInfo {
  ModelFunction function;
  const char* name;
  std::vector<std::string> inputs;  // in evaluation order, e.g. q, v, a
  bool needs_frame;
  const char* description;
};

// Every model function, with its inputs.
const std::vector<FunctionInfo>& modelFunctions();
const FunctionInfo& functionInfo(ModelFunction f);

enum class OutputKind { Value, Jacobian, Hessian };
enum class Layout { Dense, Sparse };

struct OutputSpec {
  OutputKind kind = OutputKind::Value;
  std::vector<std::string> wrt;  // Jacobian / Hessian: inputs differentiated against, in this order
  Layout layout = Layout::Dense;
  // Hessian: sum_i w_i d2 f_i / dx2 (lower triangle); the weights are a runtime input
  // block named "weights" (size of the value), or fixed numbers.
  std::optional<std::vector<double>> fixed_weights;
};

struct InputSpec {
  std::string name;
  std::optional<std::vector<double>> fixed;  // set: a constant folded into the code
};

// The x86-64 levels a spec's build may target (psABI micro-architecture levels).
inline constexpr const char* kTargetLevels[] = {"x86-64-v2", "x86-64-v3", "x86-64-v4"};

struct BuildOptions {
  std::string optimization = "O2";  // O0 | O1 | O2 | O3
  bool march_native = true;
  // The CPU the code is for, when it is not this one: an x86-64 level (kTargetLevels),
  // what a build host compiles for the robots of a fleet. Empty: march_native decides
  // (this CPU, or any x86-64). The spec's "target" also takes "native" and "x86-64",
  // which are stored as march_native true / false.
  std::string target;
  bool fast_math = false;           // never on unless asked: it changes results
  // false: only the single-knot code is compiled, about half the compile time and memory;
  // evaluate_batch then runs it knot by knot instead of several knots per SIMD register.
  bool batch = true;
};

// A spec is either a model function ("function": "rnea", the form every earlier spec
// has) or a user function ("inputs" / "define" / "outputs", user_function.hpp). For a
// user function, `inputs` lists its inputs in order and `outputs` one entry per output
// with the block's wire kind (a gradient or a vector-Jacobian product is a value-like
// vector; a Hessian without weights has the fixed weight 1), so code that only reads
// blocks handles both forms alike.
struct FunctionSpec {
  ModelFunction function = ModelFunction::Rnea;
  std::shared_ptr<const UserFunction> user;  // set: a user function
  std::vector<InputSpec> inputs;    // every input of the function, in its order
  std::vector<OutputSpec> outputs;
  std::string frame;                // fk, frame_jacobian
  ReferenceFrame reference = ReferenceFrame::LocalWorldAligned;
  BuildOptions build;

  const InputSpec& input(const std::string& name) const;
  bool isUser() const { return user != nullptr; }
  // "rnea", or the user function's name: the C name of its generated function.
  std::string functionName() const;
  // Every input's name, in order (fixed ones included).
  std::vector<std::string> inputNames() const;
};

// A spec that cannot be used. The message names the source, the field (a JSON path
// such as outputs[1].wrt[0]) and the value.
class SpecError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A spec past the limits on expression size, nesting or counts (UserFunctionLimits):
// a resource error (RESOURCE_EXHAUSTED at the service), not a mistake in meaning.
class SpecTooLarge : public SpecError {
 public:
  using SpecError::SpecError;
};

// The longest key or name (frame, function, output kind, ...) a spec may hold; past it
// parseFunctionSpec throws SpecTooLarge before the name is used or quoted anywhere.
inline constexpr std::size_t kMaxSpecNameBytes = 256;

FunctionSpec parseFunctionSpec(const std::string& json_text, const std::string& source = "<spec>");
FunctionSpec loadFunctionSpec(const std::string& path);

// The normalised JSON of a spec: defaults filled in, keys sorted, one spelling per
// meaning; equal for specs that build the same function (part of the cache key).
std::string normalizedSpecJson(const FunctionSpec& spec);

// A JSON text of the spec that parseFunctionSpec reads back to the same function (equal
// normalizedSpecJson): what is sent to a process that builds it (a robodiff-worker). A
// model function's is its normalised JSON; a user function's normalised JSON is a key
// (defines inlined into terms), so its is the function as parsed: name, inputs, shapes,
// defines, outputs and build options (descriptions left out).
std::string specJson(const FunctionSpec& spec);

const char* toString(ModelFunction f);
const char* toString(OutputKind k);

}  // namespace robodiff
