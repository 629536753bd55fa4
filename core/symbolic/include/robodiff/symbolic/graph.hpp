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
// so equal subexpressions are one node. Rewrites never reassociate or round
// differently: for finite values (and x / x for x != 0) a graph computes the same bits
// as the operations traced, up to the sign of zero (-0.0 constants are stored as 0.0).
//
// A graph has a node limit (setNodeLimit); growing past it throws GraphTooLarge, a
// resource error a caller can report, instead of exhausting memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
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

// op applied to values (unused arguments ignored): the semantics of every node, used by
// constant folding, Graph::evaluate and detached symbolic constants alike.
double evaluateOp(Op op, double a, double b = 0.0, double c = 0.0);

using NodeId = std::uint32_t;

// Thrown when a graph would grow past its node limit: a resource error (the function
// asked for is too large for the configured limits), not a bug.
class GraphTooLarge : public std::runtime_error {
 public:
  explicit GraphTooLarge(std::size_t limit);
  std::size_t limit() const { return limit_; }

 private:
  std::size_t limit_;
};

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

  // The number of inputs: one more than the largest input index created so far.
  std::uint32_t inputCount() const { return input_count_; }

  // At most `limit` nodes (the constants 0 and 1 included); creating one more throws
  // GraphTooLarge. The default keeps a runaway trace to a few GB of memory.
  static constexpr std::size_t kDefaultNodeLimit = 50'000'000;
  void setNodeLimit(std::size_t limit);
  std::size_t nodeLimit() const { return node_limit_; }

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
  static Key keyOf(const Node& n);
  void rehash(std::size_t slot_count);

  std::vector<Node> nodes_;
  // Hash-consing index: open addressing with linear probing over node ids (4 bytes a
  // slot, at most half full), the key read from nodes_; far leaner than a node-based map
  // for graphs of millions of nodes.
  static constexpr NodeId kEmptySlot = ~NodeId(0);
  std::vector<NodeId> slots_;
  std::uint32_t input_count_ = 0;
  std::size_t node_limit_ = kDefaultNodeLimit;
};

}  // namespace robodiff::symbolic
