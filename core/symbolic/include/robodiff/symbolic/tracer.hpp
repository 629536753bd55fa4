// Tracing: turn a templated algorithm into graph nodes. A Tracer hands out blocks of
// named input symbols (consecutive input indices, in the order the blocks are made) and
// turns the Sym results back into node ids.
//
//   Graph graph;
//   Tracer tracer(graph);
//   VecX<Sym> q = tracer.addInputs("q", model.nq), v = ..., a = ...;
//   Data<Sym> data(model);
//   std::vector<NodeId> tau = tracer.outputs(rnea(model, data, q, v, a));
//   graph.evaluate(tau, inputs);  // inputs: q, v, a stacked, as the blocks were made
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "robodiff/spatial/math.hpp"
#include "robodiff/symbolic/graph.hpp"
#include "robodiff/symbolic/sym.hpp"

namespace robodiff::symbolic {

struct InputBlock {
  std::string name;
  std::uint32_t first = 0;  // input index of the block's first element
  std::uint32_t size = 0;
};

class Tracer {
 public:
  // Input indices continue after those the graph already has.
  explicit Tracer(Graph& graph) : graph_(&graph) {}

  Graph& graph() const { return *graph_; }

  // `size` new inputs named name[0] .. name[size-1]. Names are unique per tracer.
  VecX<Sym> addInputs(const std::string& name, int size);

  const std::vector<InputBlock>& blocks() const { return blocks_; }
  const InputBlock& block(const std::string& name) const;  // throws std::out_of_range
  // The input indices of the named blocks, concatenated (the "wrt" of a Jacobian).
  std::vector<std::uint32_t> indices(const std::vector<std::string>& names) const;
  // "q[3]" for input index first(q) + 3; "input[k]" for an index of no block.
  std::string inputName(std::uint32_t index) const;

  // The node of a result (a detached constant becomes a constant node).
  NodeId output(const Sym& x) const { return x.nodeIn(*graph_); }
  // The nodes of a vector or matrix, row by row.
  template <class Derived> std::vector<NodeId> outputs(const Eigen::MatrixBase<Derived>& m) const {
    std::vector<NodeId> out;
    out.reserve(static_cast<std::size_t>(m.size()));
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      for (Eigen::Index c = 0; c < m.cols(); ++c) out.push_back(output(m(r, c)));
    return out;
  }

 private:
  Graph* graph_;
  std::vector<InputBlock> blocks_;
};

}  // namespace robodiff::symbolic
