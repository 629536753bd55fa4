#include "sum_chains.hpp"

#include <algorithm>
#include <limits>
#include <vector>

#include "robodiff/symbolic/cone.hpp"

namespace robodiff::codegen::detail {
namespace {

using symbolic::Graph;
using symbolic::Node;
using symbolic::Op;

constexpr NodeId kUnmapped = std::numeric_limits<NodeId>::max();

bool isSum(Op op) { return op == Op::Add || op == Op::Sub; }

// Rough cycles from operands to result on a current x86 core: what matters is the ratio
// of a chain's length to the critical path, not the exact figures.
std::uint32_t latency(Op op) {
  switch (op) {
    case Op::Constant: case Op::Input: case Op::Neg: return 0;  // negation is an operand flag
    case Op::Div: return 14;
    case Op::Sqrt: return 18;
    case Op::Sin: case Op::Cos: case Op::Tan: case Op::Asin: case Op::Acos: case Op::Atan: case Op::Atan2:
    case Op::Exp: case Op::Log: case Op::Tanh: case Op::Pow: return 40;
    default: return 4;
  }
}

class SumChainer {
 public:
  SumChainer(const Graph& g, const FunctionDefinition& f, bool ready_first) : g_(g), f_(f), ready_first_(ready_first) {}

  ChainedFunction run() {
    countUses();
    computeSlack();
    collectTerms();
    ChainedFunction out;
    out.graph.setNodeLimit(g_.nodeLimit());
    map_.assign(g_.size(), kUnmapped);
    acc_.assign(g_.size(), kUnmapped);
    std::size_t next = 0;  // into terms_, sorted by the sum that takes each
    for (NodeId id = 0; id < g_.size(); ++id) {
      if (!needed_[id]) continue;
      for (; next < terms_.size() && terms_[next].at == id; ++next) accumulate(terms_[next], out.graph);
      if (absorbed_[id]) continue;
      map_[id] = acc_[id] != kUnmapped ? acc_[id] : copy(id, out.graph);
    }
    out.function = f_;
    for (OutputBlock& b : out.function.outputs)
      for (NodeId& v : b.values) v = map_[v];
    return out;
  }

 private:
  // Uses by the needed nodes and the outputs; for a node used once, its user's op.
  void countUses() {
    std::vector<NodeId> outputs;
    for (const OutputBlock& b : f_.outputs) outputs.insert(outputs.end(), b.values.begin(), b.values.end());
    needed_ = symbolic::coneMask(g_, outputs);
    needed_.resize(g_.size(), 0);
    uses_.assign(g_.size(), 0);
    user_op_.assign(g_.size(), Op::Constant);
    for (NodeId v : outputs) ++uses_[v];
    for (NodeId id = 0; id < g_.size(); ++id) {
      if (!needed_[id]) continue;
      const Node& n = g_.node(id);
      for (int a = 0; a < symbolic::arity(n.op); ++a) {
        ++uses_[n.args[a]];
        user_op_[n.args[a]] = n.op;
      }
    }
  }

  // Earliest finish of every node (longest path from the inputs) and the latest finish
  // that keeps the function's critical path as it is.
  void computeSlack() {
    earliest_.assign(g_.size(), 0);
    std::uint32_t critical = 0;
    for (NodeId id = 0; id < g_.size(); ++id) {
      if (!needed_[id]) continue;
      const Node& n = g_.node(id);
      std::uint32_t start = 0;
      for (int a = 0; a < symbolic::arity(n.op); ++a) start = std::max(start, earliest_[n.args[a]]);
      earliest_[id] = start + latency(n.op);
      critical = std::max(critical, earliest_[id]);
    }
    latest_.assign(g_.size(), critical);
    for (NodeId id = static_cast<NodeId>(g_.size()); id-- > 0;) {
      if (!needed_[id]) continue;
      const Node& n = g_.node(id);
      for (int a = 0; a < symbolic::arity(n.op); ++a)
        latest_[n.args[a]] = std::min(latest_[n.args[a]], latest_[id] - latency(n.op));
    }
  }

  // A sum whose only user is another sum: a candidate to join that sum's chain.
  bool interior(NodeId id) const { return isSum(g_.node(id).op) && uses_[id] == 1 && isSum(user_op_[id]); }

  struct Term {
    NodeId node;  // in the source graph
    NodeId root;  // the sum (not interior) whose chain adds it
    NodeId at;    // the sum of the tree that reads it: the chain adds it where that sum was
    bool negated;
  };

  // Every term of every sum tree chained, in the order the tree's own sums read them:
  // each is added to its chain where the tree added it, left to right within one sum.
  void collectTerms() {
    absorbed_.assign(g_.size(), 0);
    std::vector<Term> tree;
    std::vector<NodeId> interiors;
    for (NodeId root = 0; root < g_.size(); ++root) {
      if (!needed_[root] || !isSum(g_.node(root).op) || interior(root)) continue;
      walkTree(root, tree, interiors);
      if (interiors.empty()) continue;  // a single sum
      if (!orderByReadiness(root, tree) && !chainFitsSlack(root, tree)) continue;  // on the critical path
      for (NodeId id : interiors) absorbed_[id] = 1;
      terms_.insert(terms_.end(), tree.begin(), tree.end());
    }
    std::stable_sort(terms_.begin(), terms_.end(), [](const Term& a, const Term& b) { return a.at < b.at; });
  }

  // The terms of the tree under `root` (sorted by the sum that reads each) and its interior sums.
  void walkTree(NodeId root, std::vector<Term>& tree, std::vector<NodeId>& interiors) const {
    tree.clear();
    interiors.clear();
    std::vector<Term> stack{{root, root, root, false}};
    while (!stack.empty()) {
      const Term t = stack.back();
      stack.pop_back();
      const Node& n = g_.node(t.node);
      if (t.node != root && !interior(t.node)) {
        tree.push_back(t);
        continue;
      }
      if (t.node != root) interiors.push_back(t.node);
      stack.push_back({n.args[1], root, t.node, n.op == Op::Sub ? !t.negated : t.negated});
      stack.push_back({n.args[0], root, t.node, t.negated});
    }
    std::stable_sort(tree.begin(), tree.end(), [](const Term& a, const Term& b) { return a.at < b.at; });
  }

  // When a chain of `terms` in this order ends (each add waits for its term).
  std::uint32_t chainEnd(const std::vector<Term>& terms) const {
    std::uint32_t end = earliest_[terms[0].node];
    for (std::size_t i = 1; i < terms.size(); ++i) end = std::max(end, earliest_[terms[i].node]) + latency(Op::Add);
    return end;
  }

  // A chain is longer than a tree (one add after another): it is used only where its end
  // stays within the slack of the tree's root, so the function's critical path does not
  // grow (a serial algorithm such as a small robot's ABA runs at the speed of that path).
  bool chainFitsSlack(NodeId root, const std::vector<Term>& tree) const { return chainEnd(tree) <= latest_[root]; }

  // The terms in the order they are ready (constants first, the latest last), all added
  // where the root was, when that chain ends sooner than both the tree and the chain in
  // the tree's order: a composite inertia's constant and early terms are summed while its
  // children's terms are computed, and the late ones join last, each in a multiply-add.
  bool orderByReadiness(NodeId root, std::vector<Term>& tree) const {
    if (!ready_first_) return false;
    std::vector<Term> ready = tree;
    std::stable_sort(ready.begin(), ready.end(),
                     [&](const Term& a, const Term& b) { return earliest_[a.node] < earliest_[b.node]; });
    if (chainEnd(ready) >= std::min(earliest_[root], chainEnd(tree))) return false;
    for (Term& t : ready) t.at = root;
    tree = std::move(ready);
    return true;
  }

  void accumulate(const Term& t, Graph& to) {
    NodeId& acc = acc_[t.root];
    if (acc == kUnmapped) acc = t.negated ? to.unary(Op::Neg, map_[t.node]) : map_[t.node];
    else acc = to.binary(t.negated ? Op::Sub : Op::Add, acc, map_[t.node]);
  }

  NodeId copy(NodeId id, Graph& to) {
    const Node& n = g_.node(id);
    switch (symbolic::arity(n.op)) {
      case 0: return n.op == Op::Constant ? to.constant(n.value) : to.input(n.index);
      case 1: return to.unary(n.op, map_[n.args[0]]);
      case 3: return to.selectPositive(map_[n.args[0]], map_[n.args[1]], map_[n.args[2]]);
      default: return to.binary(n.op, map_[n.args[0]], map_[n.args[1]]);
    }
  }

  const Graph& g_;
  const FunctionDefinition& f_;
  bool ready_first_;
  std::vector<char> needed_, absorbed_;
  std::vector<std::uint32_t> uses_, earliest_, latest_;
  std::vector<Op> user_op_;
  std::vector<Term> terms_;
  std::vector<NodeId> map_, acc_;
};

}  // namespace

ChainedFunction chainSums(const Graph& graph, const FunctionDefinition& function, bool ready_first) {
  return SumChainer(graph, function, ready_first).run();
}

}  // namespace robodiff::codegen::detail
