#include "lane_pairs.hpp"

#include <algorithm>
#include <numeric>
#include <queue>
#include <tuple>
#include <unordered_map>

#include "operand_ref.hpp"

namespace robodiff::codegen::detail {
namespace {

using symbolic::Graph;
using symbolic::NodeId;
using symbolic::Op;

// Depth of the match that ranks seeds, and the score a seed needs (about three
// operations matching).
constexpr int kSeedDepth = 4;
constexpr double kSeedScore = 3.0;
// Depth of the match that chooses between a commutative pair's two operand orders, and
// that ranks a pair's readers; the score two readers need.
constexpr int kOrderDepth = 3;
constexpr double kUpScore = 2.0;
// Rows of one column further apart than this are not tried as seeds.
constexpr std::size_t kSeedWindow = 64;
// A group of pairs is kept when it saves this many instructions more than its lane
// shuffles cost.
constexpr double kMinimumSaving = 16.0;

bool isVectorOp(Op op) { return op == Op::Add || op == Op::Sub || op == Op::Mul || op == Op::Div; }

class Chooser {
 public:
  Chooser(const Graph& g, const std::vector<char>& pairable, const ShapeSignatures& shapes, bool same_depth)
      : g_(g), pairable_(pairable), shapes_(shapes), same_depth_(same_depth), pairs_(g.size()) {}

  LanePairs run(const FunctionDefinition& f) {
    collectReaders();
    seed(f);
    pruneMarginal(f);
    prune();
    return std::move(pairs_);
  }

 private:
  Ref arg(NodeId n, int k) const { return resolve(g_, g_.node(n).args[k]); }
  bool isFree(NodeId n) const { return pairable_[n] && isVectorOp(g_.node(n).op) && !pairs_.paired(n); }
  // With same_depth_, two operations at the same depth only: neither can read the
  // other, and no two such pairs can read each other crosswise (every read goes to a
  // smaller depth), so every pair can be ordered.
  bool matchable(NodeId a, NodeId b) const {
    return a != b && isFree(a) && isFree(b) && g_.node(a).op == g_.node(b).op &&
           (!same_depth_ || depth_[a] == depth_[b]);
  }

  // How far the expressions of two operands match: constants pair as a constant
  // vector, one value read twice is a broadcast, different signs do not match.
  double operandScore(const Ref& x, const Ref& y, int depth) const {
    if (x.is_constant || y.is_constant) return x.is_constant && y.is_constant ? 0.5 : 0.0;
    if (x.negated != y.negated) return 0.0;
    if (x.base == y.base) return 0.5;
    return score(x.base, y.base, depth);
  }
  double straightScore(NodeId a, NodeId b, int depth) const {
    return operandScore(arg(a, 0), arg(b, 0), depth) + operandScore(arg(a, 1), arg(b, 1), depth);
  }
  double crossedScore(NodeId a, NodeId b, int depth) const {
    if (!symbolic::isCommutative(g_.node(a).op)) return -1.0;
    return operandScore(arg(a, 0), arg(b, 1), depth) + operandScore(arg(a, 1), arg(b, 0), depth);
  }
  double score(NodeId a, NodeId b, int depth) const {
    if (depth == 0 || !matchable(a, b)) return 0.0;
    return 1.0 + std::max(straightScore(a, b, depth - 1), crossedScore(a, b, depth - 1));
  }

  // How deep the operands of a and b match, read straight or crossed.
  int operandShapes(NodeId a, NodeId b, bool crossed) const {
    int depth = 0;
    for (int k = 0; k < 2; ++k) {
      const Ref x = arg(a, k), y = arg(b, crossed ? 1 - k : k);
      if (!x.is_constant && !y.is_constant) depth += shapes_.matchDepth(x.base, y.base);
    }
    return depth;
  }
  // A commutative pair reads its operands crossed when they match deeper that way.
  bool crossedIsBetter(NodeId a, NodeId b) const {
    const int straight = operandShapes(a, b, false), crossed = operandShapes(a, b, true);
    if (straight != crossed) return crossed > straight;
    return crossedScore(a, b, kOrderDepth) > straightScore(a, b, kOrderDepth);
  }

  // Operand signs must agree lane by lane in the order the pair reads them.
  bool signsAgree(NodeId a, NodeId b, bool crossed) const {
    for (int k = 0; k < 2; ++k) {
      const Ref x = arg(a, k), y = arg(b, crossed ? 1 - k : k);
      if (!x.is_constant && !y.is_constant && x.negated != y.negated) return false;
    }
    return true;
  }

  // Pairs a and b, then their operands while they match (depth first), then the
  // readers of every new pair while they match.
  void build(NodeId a, NodeId b) {
    const std::size_t first_new = made_.size();
    buildDown(a, b);
    for (std::size_t i = first_new; i < made_.size(); ++i) buildUp(made_[i].first, made_[i].second);
  }

  void buildDown(NodeId a, NodeId b) {
    std::vector<std::pair<NodeId, NodeId>> stack{{a, b}};
    while (!stack.empty()) {
      const auto [x, y] = stack.back();
      stack.pop_back();
      if (!matchable(x, y)) continue;
      const bool straight_ok = signsAgree(x, y, false);
      const bool crossed_ok = symbolic::isCommutative(g_.node(x).op) && signsAgree(x, y, true);
      if (!straight_ok && !crossed_ok) continue;
      const bool crossed = crossed_ok && (!straight_ok || crossedIsBetter(x, y));
      pairs_.pair(x, y, crossed);
      made_.push_back({x, y});
      for (int k = 1; k >= 0; --k) {
        const Ref u = arg(x, k), v = arg(y, crossed ? 1 - k : k);
        if (!u.is_constant && !v.is_constant) stack.push_back({u.base, v.base});
      }
    }
  }

  // A reader of x and a reader of y that match: paired, and grown down from there (the
  // output seeds reach what the outputs read; this reaches what the pairs feed, such as
  // one limb's recursion and its twin's below a sum over the limbs).
  void buildUp(NodeId x, NodeId y) {
    for (NodeId u : readers_[x]) {
      if (!isFree(u)) continue;
      NodeId best = kNoPair;
      std::pair<int, double> best_rank{-1, 0.0};  // (shape depth, score)
      for (NodeId v : readers_[y]) {
        if (!matchable(u, v)) continue;
        const std::pair<int, double> rank{shapes_.matchDepth(u, v), score(u, v, kOrderDepth)};
        if (rank.second >= kUpScore && rank > best_rank) {
          best_rank = rank;
          best = v;
        }
      }
      if (best != kNoPair) buildDown(u, best);
    }
  }

  // Who reads each operation, as the lowering reads it; each operation's depth (the
  // longest chain of operations from the inputs to it, the graph being in topological
  // order).
  void collectReaders() {
    readers_.assign(g_.size(), {});
    depth_.assign(g_.size(), 0);
    for (NodeId id = 0; id < g_.size(); ++id) {
      if (!pairable_[id]) continue;
      for (int k = 0; k < symbolic::arity(g_.node(id).op); ++k) {
        const Ref r = arg(id, k);
        if (r.is_constant || !pairable_[r.base]) continue;
        readers_[r.base].push_back(id);
        depth_[id] = std::max(depth_[id], depth_[r.base] + 1);
      }
    }
  }

  // Candidate seeds, the deepest shape matches first, then the best matches to depth 4:
  // twins, and with LanePairSeeds::TwinsAndColumns, neighbouring values of one column.
  void seed(const FunctionDefinition& f) {
    std::vector<Candidate> candidates;
    twinSeeds(f, &candidates);
    if (f.lane_pairs == LanePairSeeds::TwinsAndColumns) columnSeeds(f, &candidates);
    std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
      return std::tie(x.depth, x.score) > std::tie(y.depth, y.score);
    });
    for (const Candidate& c : candidates) build(c.a, c.b);
  }
  struct Candidate {
    int depth;     // how deep the shapes match
    double score;  // the match to depth kSeedDepth
    NodeId a, b;
  };
  void addCandidate(NodeId a, NodeId b, std::vector<Candidate>* candidates) const {
    const double s = score(a, b, kSeedDepth);
    if (s >= kSeedScore) candidates->push_back({shapes_.matchDepth(a, b), s, a, b});
  }

  // Output values anywhere in the outputs whose shapes match throughout, in output
  // order, each with the next one of the same shape: a Jacobian's entry and its twin,
  // the mirrored entry in the mirrored column (the only seeds a derivative function gets).
  void twinSeeds(const FunctionDefinition& f, std::vector<Candidate>* candidates) const {
    std::unordered_map<std::uint64_t, NodeId> waiting;  // shape -> a value still without a twin
    std::vector<char> seen(g_.size(), 0);
    for (const OutputBlock& block : f.outputs)
      for (NodeId v : block.values) {
        const Ref ref = resolve(g_, v);
        if (ref.is_constant || !isFree(ref.base) || seen[ref.base]) continue;
        seen[ref.base] = 1;
        auto [it, inserted] = waiting.try_emplace(shapes_.deepest(ref.base), ref.base);
        if (inserted) continue;
        addCandidate(it->second, ref.base, candidates);
        waiting.erase(it);
      }
  }

  // Output values of one column of a dense block, near each other (a value vector's
  // entries). Not for derivative functions: a Jacobian's column pairs derivatives of
  // unrelated entries, which share too much with scalar code (Panda RNEA + J 1.22 ->
  // 1.44 us with 966 such pairs).
  void columnSeeds(const FunctionDefinition& f, std::vector<Candidate>* candidates) const {
    for (const OutputBlock& block : f.outputs) {
      if (block.kind != OutputKind::Dense || block.cols == 0) continue;
      for (std::uint32_t c = 0; c < block.cols; ++c) {
        std::vector<NodeId> values;
        for (std::uint32_t r = 0; r < block.rows; ++r) {
          const Ref ref = resolve(g_, block.values[r * block.cols + c]);
          if (!ref.is_constant && isFree(ref.base)) values.push_back(ref.base);
        }
        for (std::size_t i = 0; i < values.size(); ++i)
          for (std::size_t j = i + 1; j < values.size() && j <= i + kSeedWindow; ++j)
            addCandidate(values[i], values[j], candidates);
      }
    }
  }

  // Extra instructions a pair's operand costs: none for a pair computed in the same
  // lanes or two constants, a broadcast for one value read twice, else an insertion.
  double operandCost(const Ref& x, const Ref& y) const {
    if (x.is_constant && y.is_constant) return 0.0;
    if (x.is_constant || y.is_constant || x.negated != y.negated) return 1.0;
    if (x.base == y.base) return 0.5;
    if (pairs_.paired(x.base) && pairs_.partner(x.base) == y.base && pairs_.lane(x.base) == 0) return 0.0;
    return 1.0;
  }

  // Which values scalar code reads (a member of no pair reading them).
  std::vector<char> scalarReaders() const {
    std::vector<char> scalar_reader(g_.size(), 0);
    for (NodeId id = 0; id < g_.size(); ++id) {
      if (!pairable_[id] || pairs_.paired(id)) continue;
      for (int k = 0; k < symbolic::arity(g_.node(id).op); ++k) {
        const Ref r = arg(id, k);
        if (!r.is_constant) scalar_reader[r.base] = 1;
      }
    }
    return scalar_reader;
  }

  // Dissolves the pairs that cost more than they save on their own, pass after pass
  // until none does: a pair saves its instruction, and an insertion for each operand of
  // a pair that reads it in the same lanes; it costs its operands' insertions and an
  // extraction when scalar code reads lane 1 (shuffleCost each).
  void pruneMarginal(const FunctionDefinition& f) {
    const NodeId n = static_cast<NodeId>(g_.size());
    const double w = shuffleCost(f);
    for (int pass = 0; pass < kMarginalPasses; ++pass) {
      const std::vector<char> scalar_reader = scalarReaders();
      std::vector<double> margin(n, 0.0);
      for (NodeId a = 0; a < n; ++a) {
        if (!pairs_.paired(a) || pairs_.lane(a) != 0) continue;
        const NodeId b = pairs_.partner(a);
        margin[a] += 1.0 - (scalar_reader[b] ? w : 0.0);
        for (int k = 0; k < 2; ++k) {
          const Ref x = arg(a, k), y = arg(b, pairs_.swapped(b) ? 1 - k : k);
          const double c = operandCost(x, y);
          margin[a] -= c * w;
          if (c == 0.0 && !x.is_constant) margin[x.base] += 1.0;  // x's pair spares this insertion
        }
      }
      bool changed = false;
      for (NodeId a = 0; a < n; ++a)
        if (pairs_.paired(a) && pairs_.lane(a) == 0 && margin[a] < 0.0) {
          pairs_.dissolve(a);
          changed = true;
        }
      if (!changed) return;
    }
  }
  static constexpr int kMarginalPasses = 32;
  // What an insertion or an extraction costs, in instructions. A derivative function's
  // twins sit among more scalar code (the terms a free-flyer's base and torso share
  // with every limb): counted at 1, the free-flying Talos's RNEA + J kept 13,657 pairs
  // with 7,232 insertions and ran 10% slower than without pairs; at 1.5, 7,374 pairs
  // with 1,617 insertions, 12% faster (docs/code-generation.md).
  static double shuffleCost(const FunctionDefinition& f) {
    return f.lane_pairs == LanePairSeeds::Twins ? 1.5 : 1.0;
  }

  // Keeps the groups of connected pairs (a pair reading another as its operand) that
  // save at least kMinimumSaving instructions: each pair saves one, each operand built
  // from two scalars costs one, each lane 1 read by scalar code costs an extraction.
  void prune() {
    const NodeId n = static_cast<NodeId>(g_.size());
    const std::vector<char> scalar_reader = scalarReaders();
    std::vector<NodeId> parent(n);
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](NodeId x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    std::vector<double> saving(n, 0.0);
    for (NodeId a = 0; a < n; ++a) {
      if (!pairs_.paired(a) || pairs_.lane(a) != 0) continue;
      const NodeId b = pairs_.partner(a);
      double cost = scalar_reader[b] ? 1.0 : 0.0;
      for (int k = 0; k < 2; ++k) {
        const Ref x = arg(a, k), y = arg(b, pairs_.swapped(b) ? 1 - k : k);
        const double c = operandCost(x, y);
        cost += c;
        if (c == 0.0 && !x.is_constant) parent[find(x.base)] = find(a);
      }
      saving[a] = 1.0 - cost;
    }
    std::vector<double> group(n, 0.0);
    for (NodeId a = 0; a < n; ++a)
      if (pairs_.paired(a) && pairs_.lane(a) == 0) group[find(a)] += saving[a];
    for (NodeId a = 0; a < n; ++a)
      if (pairs_.paired(a) && pairs_.lane(a) == 0 && group[find(a)] < kMinimumSaving) pairs_.dissolve(a);
  }

  const Graph& g_;
  const std::vector<char>& pairable_;
  const ShapeSignatures& shapes_;
  const bool same_depth_;
  LanePairs pairs_;
  std::vector<std::vector<NodeId>> readers_;
  std::vector<std::uint32_t> depth_;
  std::vector<std::pair<NodeId, NodeId>> made_;  // pairs in the order they were made
};

// One attempt at ordering a function's steps with each pair as one unit; returns false
// after dissolving a pair that could not be ordered.
class PairOrder {
 public:
  PairOrder(const Graph& g, const std::vector<Step>& steps, LanePairs& pairs) : g_(g), steps_(steps), pairs_(pairs) {}

  bool attempt(std::vector<Step>* out) {
    makeUnits();
    std::vector<std::vector<std::uint32_t>> readers(units_.size());
    std::vector<std::uint32_t> waiting(units_.size(), 0);
    for (std::uint32_t u = 0; u < units_.size(); ++u)
      for (NodeId node : {units_[u].first, units_[u].second, units_[u].lane1}) {
        if (node == kNoPair) continue;
        for (int k = 0; k < symbolic::arity(g_.node(node).op); ++k) {
          const Ref r = resolve(g_, g_.node(node).args[k]);
          if (r.is_constant) continue;
          auto it = unit_of_.find(r.base);
          if (it == unit_of_.end()) continue;  // an input
          if (it->second == u) {  // one member reads the other
            pairs_.dissolve(units_[u].first);
            return false;
          }
          readers[it->second].push_back(u);
          ++waiting[u];
        }
      }
    using Entry = std::pair<std::uint32_t, std::uint32_t>;  // (position, unit)
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> ready;
    for (std::uint32_t u = 0; u < units_.size(); ++u)
      if (waiting[u] == 0) ready.push({position_[u], u});
    out->clear();
    while (!ready.empty()) {
      const std::uint32_t u = ready.top().second;
      ready.pop();
      out->push_back(units_[u]);
      for (std::uint32_t r : readers[u])
        if (--waiting[r] == 0) ready.push({position_[r], r});
    }
    if (out->size() == units_.size()) return true;
    // A cycle through pairs: dissolve the earliest pair still waiting (after many
    // attempts, every pair still waiting: the cost of a retry is the whole order).
    std::uint32_t victim = kNoPair;
    const bool all = ++attempts_ > kPatientAttempts;
    for (std::uint32_t u = 0; u < units_.size(); ++u) {
      if (waiting[u] == 0 || units_[u].lane1 == kNoPair) continue;
      if (all) pairs_.dissolve(units_[u].first);
      else if (victim == kNoPair || position_[u] < position_[victim]) victim = u;
    }
    if (!all) pairs_.dissolve(units_[victim].first);
    return false;
  }

 private:
  // A unit per step, the two steps of a pair merged at the later one's position.
  void makeUnits() {
    units_.clear();
    position_.clear();
    unit_of_.clear();
    for (std::uint32_t i = 0; i < steps_.size(); ++i) {
      const Step& s = steps_[i];
      if (!pairs_.paired(s.first)) {
        addUnit(s, i);
        continue;
      }
      const NodeId lane0 = pairs_.lane(s.first) == 0 ? s.first : pairs_.partner(s.first);
      auto it = unit_of_.find(lane0);
      if (it != unit_of_.end()) {
        position_[it->second] = i;
        unit_of_[s.first] = it->second;
        continue;
      }
      addUnit(Step{lane0, kNoPair, pairs_.partner(lane0), s.chunk}, i);
    }
  }
  void addUnit(const Step& s, std::uint32_t position) {
    const std::uint32_t u = static_cast<std::uint32_t>(units_.size());
    units_.push_back(s);
    position_.push_back(position);
    for (NodeId node : {s.first, s.second, s.lane1})
      if (node != kNoPair) unit_of_[node] = u;
  }

  static constexpr int kPatientAttempts = 64;

  const Graph& g_;
  const std::vector<Step>& steps_;
  LanePairs& pairs_;
  int attempts_ = 0;
  std::vector<Step> units_;
  std::vector<std::uint32_t> position_;
  std::unordered_map<NodeId, std::uint32_t> unit_of_;
};

}  // namespace

void LanePairs::pair(NodeId lane0, NodeId lane1, bool swapped) {
  partner_[lane0] = lane1;
  partner_[lane1] = lane0;
  lane_[lane0] = 0;
  lane_[lane1] = 1;
  swapped_[lane0] = 0;
  swapped_[lane1] = swapped ? 1 : 0;
  ++count_;
}

void LanePairs::dissolve(NodeId n) {
  const NodeId other = partner_[n];
  if (other == kNoPair) return;
  partner_[n] = partner_[other] = kNoPair;
  swapped_[n] = swapped_[other] = 0;
  --count_;
}

LanePairs chooseLanePairs(const Graph& graph, const FunctionDefinition& function,
                          const std::vector<char>& pairable, const ShapeSignatures& shapes, bool same_depth) {
  return Chooser(graph, pairable, shapes, same_depth).run(function);
}

LanePairs scheduleLanePairs(const Graph& graph, const FunctionDefinition& function, double coverage,
                            std::uint32_t below, std::vector<Step>& steps) {
  std::uint32_t operations = 0;
  std::vector<char> pairable(graph.size(), 0);
  for (const Step& s : steps) {
    operations += s.second == kNoPair ? 1 : 2;
    if (s.second == kNoPair) pairable[s.first] = 1;  // sin and cos steps do not pair
  }
  LanePairs kept(graph.size());
  if (operations >= below || function.lane_pairs == LanePairSeeds::None) return kept;
  // Solo-12's ABA value paired 1,400 operations at one depth and 411 at any; Talos's
  // 2,076 and 3,818.
  std::vector<Step> ordered;
  const ShapeSignatures shapes(graph, pairable);
  for (bool same_depth : {true, false}) {
    LanePairs pairs = chooseLanePairs(graph, function, pairable, shapes, same_depth);
    if (pairs.count() <= kept.count()) continue;
    std::vector<Step> order = orderWithPairs(graph, steps, pairs);
    if (pairs.count() <= kept.count()) continue;
    kept = std::move(pairs);
    ordered = std::move(order);
  }
  if (kept.count() == 0 || 2.0 * static_cast<double>(kept.count()) < coverage * operations)
    return LanePairs(graph.size());
  steps = std::move(ordered);
  return kept;
}

std::vector<Step> orderWithPairs(const Graph& graph, const std::vector<Step>& steps, LanePairs& pairs) {
  PairOrder order(graph, steps, pairs);
  std::vector<Step> out;
  while (!order.attempt(&out)) {
  }
  return out;
}

}  // namespace robodiff::codegen::detail
