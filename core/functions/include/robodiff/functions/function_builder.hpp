// From a spec and a model to the function that is generated: trace the model function
// on symbolic scalars, differentiate what the outputs ask for, and assemble a compact
// graph whose inputs are exactly the function's runtime inputs.
//
// How each output is built:
// - value: the traced model function (fixed inputs are constants and fold away);
// - Jacobian: symbolic differentiation of the trace (forward or reverse by shape),
//   except forward dynamics, whose Jacobian is assembled from the analytic identities
//   (Carpentier & Mansard 2018) d ddq/d(q, v) = -M^-1 d RNEA/d(q, v) at a = ddq and
//   d ddq/d tau = M^-1: smaller graphs than differentiating ABA itself (measured in
//   tests/functions/function_builder_test.cpp and written down in core/functions/README.md);
// - Hessian: sum_i w_i d2 f_i / dx2 with the weights a runtime input block "weights"
//   (one weight per value entry) or constants.
// With a floating base, q-derivatives are in the tangent space (nv columns, the golden
// files' convention): the trace runs at q (+) dq and is differentiated at dq = 0.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff {

enum class AbaJacobianMethod {
  Analytic,       // -M^-1 d RNEA / d(q, v) at a = ddq, and M^-1 (the default: smaller)
  Differentiate,  // differentiate the traced ABA
};

enum class AbaValueMethod {
  Articulated,  // ABA (dynamics/aba.hpp)
  Factors,      // M^-1 (tau - nle) by M's tree factors (dynamics/minv.hpp)
  Cheaper,      // a value-only ABA built both ways, the one with fewer operations kept
};

enum class RneaJacobianMethod {
  Analytic,       // dynamics/rnea_derivatives.hpp traced, the value from the same sweep
  Differentiate,  // reverse/forward-mode differentiation of the traced RNEA
  Cheaper,        // both built; the analytic one kept when it needs at most
                  // kAnalyticRneaInstructionsRatio of the other's instructions
};

// The analytic RNEA derivatives keep more values alive across their sweeps (composite
// inertias and Coriolis composites): their code is faster only when it saves enough.
// Measured on eleven robots without lane pairs (docs/code-generation.md), the analytic
// code was the faster up to 0.90 of the operations (Bolt, 0.90: 1.86 against 2.07 µs;
// Solo-12, 0.82: 3.34 against 3.95) and twice as slow at the UR5's 1.18 (0.79 against
// 0.40). With lane pairs the ways are compared by their single-knot instructions
// (builtInstructions): where the legs are twins, differentiation pairs more (Solo-12:
// 8,616 pairs in 19,172 operations, 2.32 µs; analytic 4,087 in 15,853, 2.75 µs). On
// the seven robots measured both ways (and the UR5, which has no pairs, before), the one
// with fewer instructions was the faster, the closest Go1's (0.994: 2.70 against 2.85
// µs), so no margin is left.
inline constexpr double kAnalyticRneaInstructionsRatio = 1.0;

struct FunctionBuilderOptions {
  std::string name;  // the C name of the function; empty: the spec's function name
  AbaJacobianMethod aba_jacobian = AbaJacobianMethod::Analytic;
  // ABA's value where no Jacobian comes with it (with one, the value comes from the
  // derivatives' sweep): the factors are smaller on fixed bases and small robots (Panda
  // 1,682 operations against 2,164; 227 against 321 ns), ABA on the free-flying Talos.
  AbaValueMethod aba_value = AbaValueMethod::Cheaper;
  // The RNEA Jacobian: which method gives faster code depends on the robot (the UR5's
  // aligned axes favour differentiation: 3.7k operations against 4.6k analytic; the
  // Talos goes analytic), so both are built (tracing takes milliseconds) and compared
  // (kAnalyticRneaInstructionsRatio). ABA's partials are faster analytic (Talos ABA
  // Jacobian 8.2 µs against 10.0; Panda 1.49 against 1.47).
  RneaJacobianMethod rnea_jacobian = RneaJacobianMethod::Cheaper;
  RneaJacobianMethod aba_rnea_partials = RneaJacobianMethod::Analytic;  // d RNEA/d(q, v) in ABA's Jacobian
  symbolic::JacobianMode jacobian_mode = symbolic::JacobianMode::Automatic;
  // Node limit of the trace graph; beyond it the build fails with GraphTooLarge.
  std::size_t node_limit = symbolic::Graph::kDefaultNodeLimit;
};

// One output block of a built function, as a user reads it.
struct BuiltOutput {
  std::string name;  // the block's name in the library: value, jacobian, hessian, ...
  OutputKind kind = OutputKind::Value;
  std::vector<std::string> wrt;  // Jacobian / Hessian
  Layout layout = Layout::Dense;
  // value: the function's rows x cols (row-major); Jacobian: value entries x tangent
  // sizes of wrt; Hessian: n x n, dense = the full symmetric matrix, sparse = the
  // nonzeros of the lower triangle in CSR.
  int rows = 0, cols = 0;
  std::uint32_t nnz = 0;  // doubles written
};

struct BuildTimings {
  double trace_seconds = 0;           // the model function on symbolic scalars
  double differentiate_seconds = 0;   // Jacobians and Hessians
  double assemble_seconds = 0;        // the compact graph of the function's inputs
};

struct BuiltFunction {
  std::unique_ptr<symbolic::Graph> graph;  // holds exactly what the outputs need
  codegen::FunctionDefinition definition;  // input blocks: variable inputs in order, then "weights"
  std::vector<BuiltOutput> outputs;        // one per spec output, in order
  int value_rows = 0, value_cols = 0;
  std::size_t trace_nodes = 0;             // size of the working graph before assembly
  std::string method;                      // how the derivatives were built, in words
  BuildTimings timings;
  // User functions with derivatives: operations with the primitives' own derivative
  // rules (what is built), and differentiating the primitives' traces instead (0: not
  // built, e.g. past the node limit).
  std::size_t rule_operations = 0, traced_operations = 0;
};

// Throws SpecError when the spec does not fit the model (a fixed input of the wrong
// size, an unknown frame, a weight count that differs from the value's size) and
// symbolic::GraphTooLarge past options.node_limit.
BuiltFunction buildFunction(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options = {});

// Arithmetic operations the function's outputs need (what its generated code computes).
std::size_t builtOperations(const BuiltFunction& f);

// The instructions of its single-knot code under the library's default code generation
// (codegen::singleKnotInstructions): the operations, less one per lane pair. Lowers the
// function; buildFunction has set the definition's lane-pair seeds.
std::size_t builtInstructions(const BuiltFunction& f);

}  // namespace robodiff
