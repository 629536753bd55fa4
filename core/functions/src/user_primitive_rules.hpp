// A model primitive traced with its tangent: the value in the function's graph, and
// d value = sum over arguments of (partials w.r.t. the argument) x (argument's tangent).
// Which partials (docs/function-language.md, "Derivatives through primitives"):
//  - rnea: the analytic RNEA derivatives (Carpentier & Mansard), value from the same sweep;
//  - aba: ddq's tangent is M^-1 (d tau - d rnea/dq dq - d rnea/dv dv) at a = ddq, the
//    right-hand side built first and solved with M's tree factors;
//  - distance: the nearest points held fixed on their bodies (normal . point Jacobians);
//  - every other primitive, and all of them when rules are off: the primitive traced on
//    fresh inputs in a scratch graph, differentiated there (forward or reverse mode,
//    whichever needs fewer sweeps) and copied in with its inputs replaced by the
//    arguments. Configuration arguments are moved in the tangent space (q (+) dq at dq = 0).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "user_primitives.hpp"

namespace robodiff::detail {

struct PrimitiveCall {
  const PrimitiveContext& context;
  const std::string& name;
  const std::vector<VecX<symbolic::Sym>>& vectors;  // configurations as coordinates; empty for strings
  const std::vector<std::string>& strings;          // string arguments; empty for vectors
  const std::vector<const Value<symbolic::Sym>*>& args;
  // The primitive's value at other vector arguments (the same strings).
  std::function<MatX<symbolic::Sym>(const std::vector<VecX<symbolic::Sym>>&, const std::vector<std::string>&)> value;
};

Value<symbolic::Sym> tracePrimitive(const PrimitiveCall& call);

// A product of symbolic matrices that skips structural zeros (most tangent entries are).
MatX<symbolic::Sym> sparseProduct(const MatX<symbolic::Sym>& a, const MatX<symbolic::Sym>& b);

// X = M^-1 B with M = L^T D L as factorizeMassMatrix leaves it (lower triangle of LD),
// column by column, following the tree (dynamics/minv.hpp): L is nonzero only along
// ancestor chains, so most products are with structural zeros and fold away.
MatX<symbolic::Sym> solveWithMassFactors(const Model& model, const MatX<symbolic::Sym>& LD, const MatX<symbolic::Sym>& B);

}  // namespace robodiff::detail
