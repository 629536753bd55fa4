// Second derivatives as graph nodes: the weighted Hessian sum_i w_i d^2 f_i / dx^2 (the
// Lagrangian Hessian of an optimiser, with the weights as constants or as inputs of the
// graph) and the Hessian of a scalar cost. Symmetric, so only the lower triangle is kept.
//
// Built as the Jacobian of one reverse-mode gradient (forward-over-reverse or
// reverse-over-reverse, whichever jacobian's automatic choice finds smaller).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "robodiff/symbolic/differentiation.hpp"

namespace robodiff::symbolic {

struct Hessian {
  int n = 0;
  // The lower triangle row by row: (0,0), (1,0), (1,1), (2,0), ... (n (n+1) / 2 nodes).
  std::vector<NodeId> lower;
  JacobianMode mode = JacobianMode::Forward;  // how the gradient was differentiated

  // Entry (i, j) for any i, j (symmetric).
  NodeId operator()(int i, int j) const {
    if (i < j) std::swap(i, j);
    return lower[static_cast<std::size_t>(i) * (i + 1) / 2 + j];
  }
  // The structurally nonzero entries of the lower triangle, and their nodes in CSR order.
  SparsityPattern pattern() const;
  std::vector<NodeId> nonzeros() const;
};

// sum_i weights[i] d^2 outputs[i] / d wrt^2.
Hessian weightedHessian(Graph& graph, const std::vector<NodeId>& outputs, const std::vector<NodeId>& weights,
                        const std::vector<std::uint32_t>& wrt, JacobianMode mode = JacobianMode::Automatic);
// ... with constant weights.
Hessian weightedHessian(Graph& graph, const std::vector<NodeId>& outputs, const std::vector<double>& weights,
                        const std::vector<std::uint32_t>& wrt, JacobianMode mode = JacobianMode::Automatic);

// d^2 cost / d wrt^2.
Hessian hessian(Graph& graph, NodeId cost, const std::vector<std::uint32_t>& wrt,
                JacobianMode mode = JacobianMode::Automatic);

}  // namespace robodiff::symbolic
