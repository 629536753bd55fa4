// Symbolic differentiation: derivatives are new nodes of the same graph, so they are
// simplified, shared and generated like any other result (differentiate, then
// generate, as CasADi's SX does).
//
// Every pass is a loop over node ids (the node array is a topological order), never a
// recursion, so graphs of millions of nodes are fine. Derivative rules exist for every
// Op; those of abs, min, max and selectPositive select between tangents with
// selectPositive (branch-free; at a tie min/max take the second argument's, abs the
// negative side's).
//
// Inputs are named by their input index (Tracer::indices gives those of named blocks).
// A derivative that is structurally zero is the constant node 0 (Graph::zero()).
#pragma once

#include <cstdint>
#include <vector>

#include "robodiff/symbolic/graph.hpp"
#include "robodiff/symbolic/sparsity.hpp"

namespace robodiff::symbolic {

enum class JacobianMode {
  Automatic,  // the mode with fewer sweeps; at a tie, as Smallest
  Forward,    // one sweep per input (column)
  Reverse,    // one sweep per output (row)
  Smallest,   // both run; the one that added fewer nodes is kept (twice the work, a graph copy)
};
// Fewer sweeps is not always the smaller result: sweeps of forward mode touch only what
// depends on their input, those of reverse mode the whole cone of their output. For ABA
// w.r.t. [q, v, tau] forward mode is ~3x smaller than reverse mode although it needs 3x
// the sweeps (see tests/symbolic/graph_size_test.cpp); Smallest finds that out.

const char* toString(JacobianMode mode);

struct Jacobian {
  int rows = 0, cols = 0;
  std::vector<NodeId> entries;  // row-major, rows x cols; Graph::zero() where structurally zero
  JacobianMode mode = JacobianMode::Forward;  // the mode that built it (Forward or Reverse)

  NodeId operator()(int row, int col) const { return entries[static_cast<std::size_t>(row) * cols + col]; }
  // The entries that are not the constant 0, and their nodes in the same (CSR) order.
  SparsityPattern pattern() const { return patternOfNodes(rows, cols, entries); }
  std::vector<NodeId> nonzeros() const;
};

// d outputs / d inputs `wrt`: outputs.size() x wrt.size().
Jacobian jacobian(Graph& graph, const std::vector<NodeId>& outputs, const std::vector<std::uint32_t>& wrt,
                  JacobianMode mode = JacobianMode::Automatic);

// Forward mode, one direction: sum_j d outputs / d wrt[j] * direction[j] (direction:
// nodes, e.g. inputs or constants). One sweep.
std::vector<NodeId> directionalDerivative(Graph& graph, const std::vector<NodeId>& outputs,
                                          const std::vector<std::uint32_t>& wrt,
                                          const std::vector<NodeId>& direction);

// Reverse mode, one sweep: d (sum_i weights[i] * outputs[i]) / d wrt, as wrt.size() nodes.
std::vector<NodeId> weightedGradient(Graph& graph, const std::vector<NodeId>& outputs,
                                     const std::vector<NodeId>& weights, const std::vector<std::uint32_t>& wrt);

// d output / d wrt for one scalar output.
std::vector<NodeId> gradient(Graph& graph, NodeId output, const std::vector<std::uint32_t>& wrt);

}  // namespace robodiff::symbolic
