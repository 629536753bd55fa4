// The model primitives of the expression language (rnea, aba, crba, frame_position,
// integrate, distance, ...): their signatures, their values on any scalar S, and, when
// tracing, their tangents. A primitive's tangent is the product of its partials with
// its arguments' tangents (the chain rule at the block level). The partials come from
// the primitive's own rule where it has one (rnea: the analytic derivatives; aba:
// -M^-1 d rnea/d(q, v) and M^-1, applied by solves with M's tree factors; distance: the
// nearest points' Jacobians), else from differentiating the primitive's trace in a
// scratch graph (user_primitive_rules.hpp).
#pragma once

#include <string>
#include <vector>

#include "robodiff/functions/user_function.hpp"
#include "robodiff/model/model.hpp"
#include "user_value.hpp"

namespace robodiff::detail {

enum class ArgKind {
  Configuration,  // nq coordinates (a "configuration" input, integrate(...)), tangent nv
  Velocity,       // nv entries
  Frame,          // a string: a frame of the model
  Reference,      // a string: LOCAL, WORLD or LOCAL_WORLD_ALIGNED (optional, last)
  Shape,          // a string: a shape of the spec's "shapes"
};

struct PrimitiveSignature {
  const char* name;
  std::vector<ArgKind> args;
  const char* result;  // in words, for the reference and errors
};

const std::vector<PrimitiveSignature>& primitiveSignatures();
const PrimitiveSignature* findPrimitive(const std::string& name);

// What a primitive needs to know besides its arguments.
struct PrimitiveContext {
  const Model& model;
  const UserFunction& function;
  bool primitive_rules = true;  // false: every primitive's partials by differentiating its trace
  std::size_t node_limit = 0;   // of scratch graphs
  symbolic::Graph* graph = nullptr;  // tracing: the graph the function is traced into
  bool aba_by_factors = false;  // aba's value as M^-1 (tau - nle) by M's tree factors (minv.hpp)
};

// One argument as the evaluator hands it over: a value, or a string literal.
template <class S> struct PrimitiveArg {
  Value<S> value;
  std::string text;
  bool is_string = false;
  int column = 1;
};

// The primitive's value (double) / value and tangent (Sym). Checks every argument's
// kind and size, and frame, shape and reference names (EvalError with the closest names).
Value<double> callPrimitive(const PrimitiveContext& context, const PrimitiveSignature& signature,
                            const std::vector<PrimitiveArg<double>>& args, int column);
Value<symbolic::Sym> callPrimitive(const PrimitiveContext& context, const PrimitiveSignature& signature,
                                   const std::vector<PrimitiveArg<symbolic::Sym>>& args, int column);

// Whether the model's root is a free-flyer: its configurations then live on a manifold
// (nq = nv + 1), and their derivatives are taken in the tangent space.
inline bool hasFreeFlyer(const Model& model) { return model.root == RootJoint::FreeFlyer; }

// The frame index of a frame name (-1 for "world"); EvalError with the closest names.
int resolveFrameName(const Model& model, const std::string& name, int column);

}  // namespace robodiff::detail
