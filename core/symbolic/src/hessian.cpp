#include "robodiff/symbolic/hessian.hpp"

#include <stdexcept>

namespace robodiff::symbolic {

SparsityPattern Hessian::pattern() const {
  SparsityPattern p;
  p.rows = p.cols = n;
  p.row_ptr.push_back(0);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j <= i; ++j)
      if ((*this)(i, j) != 0) p.col_idx.push_back(j);
    p.row_ptr.push_back(static_cast<int>(p.col_idx.size()));
  }
  return p;
}

std::vector<NodeId> Hessian::nonzeros() const {
  std::vector<NodeId> out;
  for (NodeId e : lower)
    if (e != 0) out.push_back(e);  // packed row-by-row order is CSR order
  return out;
}

Hessian weightedHessian(Graph& graph, const std::vector<NodeId>& outputs, const std::vector<NodeId>& weights,
                        const std::vector<std::uint32_t>& wrt, JacobianMode mode) {
  const std::vector<NodeId> grad = weightedGradient(graph, outputs, weights, wrt);
  const Jacobian jac = jacobian(graph, grad, wrt, mode);
  Hessian h;
  h.n = static_cast<int>(wrt.size());
  h.mode = jac.mode;
  h.lower.reserve(wrt.size() * (wrt.size() + 1) / 2);
  for (int i = 0; i < h.n; ++i)
    for (int j = 0; j <= i; ++j) h.lower.push_back(jac(i, j));
  return h;
}

Hessian weightedHessian(Graph& graph, const std::vector<NodeId>& outputs, const std::vector<double>& weights,
                        const std::vector<std::uint32_t>& wrt, JacobianMode mode) {
  std::vector<NodeId> nodes;
  nodes.reserve(weights.size());
  for (double w : weights) nodes.push_back(graph.constant(w));
  return weightedHessian(graph, outputs, nodes, wrt, mode);
}

Hessian hessian(Graph& graph, NodeId cost, const std::vector<std::uint32_t>& wrt, JacobianMode mode) {
  return weightedHessian(graph, std::vector<NodeId>{cost}, std::vector<NodeId>{graph.one()}, wrt, mode);
}

}  // namespace robodiff::symbolic
