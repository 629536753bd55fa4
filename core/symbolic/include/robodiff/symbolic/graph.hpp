// The expression graph: an append-only, hash-consed DAG of scalar operations.
//
// Nodes are stored in creation order, and a node's arguments always have smaller ids,
// so the node array is already a topological order: every pass over the graph
// (evaluation, differentiation, code generation) is a loop, never a recursion, and
// humanoid-sized graphs (10^5 - 10^6 nodes) are fine.
//
// Construction simplifies: constants are folded, identities applied (x + 0, x * 1,
// x * 0, x - x, -(-x), ...), the operands of commutative operations put in canonical
// order, and an operation equal to an existing node returns that node (hash-consing),
// so equal subexpressions are one node.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace robodiff::symbolic {

enum class Op : std::uint8_t {
  // Leaves.
  Constant,  // value
  Input,     // the input with index `index`
  // Unary.
  Neg, Sin, Cos, Tan, Asin, Acos, Atan, Exp, Log, Sqrt, Tanh, Abs,
  // Binary.
  Add, Sub, Mul, Div, Atan2, Pow, Min, Max,
  // Ternary: a > 0 ? b : c, evaluated without a branch.
  SelectPositive,
};

const char* toString(Op op);
int arity(Op op);  // 0, 1, 2 or 3
bool isCommutative(Op op);

using NodeId = std::uint32_t;

struct Node {
  Op op = Op::Constant;
  NodeId args[3] = {0, 0, 0};
  double value = 0.0;        // Constant: the value
  std::uint32_t index = 0;   // Input: the input index
};

class Graph {
 public:
  Graph();

  NodeId constant(double value);
  NodeId input(std::uint32_t index);
  NodeId unary(Op op, NodeId a);
  NodeId binary(Op op, NodeId a, NodeId b);
  NodeId selectPositive(NodeId condition, NodeId if_positive, NodeId otherwise);

  const Node& node(NodeId id) const { return nodes_[id]; }
  std::size_t size() const { return nodes_.size(); }
  const std::vector<Node>& nodes() const { return nodes_; }

  bool isConstant(NodeId id, double value) const {
    return nodes_[id].op == Op::Constant && nodes_[id].value == value;
  }

  // The ids of the constants 0 and 1 (always present).
  NodeId zero() const { return 0; }
  NodeId one() const { return 1; }

  // Evaluates every node reachable from `outputs` at `inputs` in double (a reference
  // for tests and the interpreter's check; not fast).
  std::vector<double> evaluate(const std::vector<NodeId>& outputs, const std::vector<double>& inputs) const;

 private:
  NodeId add(const Node& n);  // hash-consing insert of an already simplified node

  struct Key {
    Op op;
    NodeId a, b, c;
    std::uint64_t bits;  // constant value bits or input index
    bool operator==(const Key& o) const {
      return op == o.op && a == o.a && b == o.b && c == o.c && bits == o.bits;
    }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const;
  };
  std::vector<Node> nodes_;
  std::unordered_map<Key, NodeId, KeyHash> index_;
};

}  // namespace robodiff::symbolic
