// One build of a built-in model function (RNEA, ABA, CRBA, ...) with the derivative
// methods `options` names: trace the value, take the derivatives the spec asks for
// (analytic RNEA partials, ABA's Jacobian from them, or symbolic differentiation), and
// assemble the function's graph and output blocks. buildFunction (function_builder.cpp)
// chooses the methods; the maths is in docs/code-generation.md.
#pragma once

#include "robodiff/functions/function_builder.hpp"

namespace robodiff::detail {

// Never called with RneaJacobianMethod::Cheaper (buildFunction resolves it first).
BuiltFunction buildModelFunction(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options);

}  // namespace robodiff::detail
