#pragma once
// The generated functions trajectory optimisation evaluates at every knot, both inverse
// dynamics of the knot's (q, v, a):
//   first order   tau and d tau / d(q, v, a) (nv x 3nv, dense row-major, columns q | v | a);
//                 all that the objective, its gradient and the torque constraints need;
//   second order  sum_i w_i d2 tau_i / d(q, v, a)^2 with the weights a runtime input
//                 (the lower triangle of the 3nv x 3nv matrix in CSR: structural zeros,
//                 such as the whole a-a block, are neither computed nor assembled).
// Two functions, not one: Ipopt evaluates the objective at trial points far more often
// than the Hessian, and the weights (2 w c_k tau_k + lambda_k) need tau first.

#include <string>
#include <utility>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

class TrajectoryFunctions {
 public:
  // Builds or loads both (compiled: through the cache and robodiff-worker; interpreted:
  // at once). `urdf_text` is the text `model` was loaded from.
  static TrajectoryFunctions open(const Model& model, const std::string& urdf_text,
                                  const BatchFunctionOptions& options = {});

  static FunctionSpec firstOrderSpec();
  static FunctionSpec secondOrderSpec();

  const BatchFunction& firstOrder() const { return first_order_; }
  const BatchFunction& secondOrder() const { return second_order_; }

 private:
  TrajectoryFunctions(BatchFunction first_order, BatchFunction second_order)
      : first_order_(std::move(first_order)), second_order_(std::move(second_order)) {}
  BatchFunction first_order_, second_order_;
};

}  // namespace robodiff::batch
