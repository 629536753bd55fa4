#include "step_schedule.hpp"

#include <unordered_map>

#include "emission_order.hpp"
#include "operand_ref.hpp"

namespace robodiff::codegen::detail {
namespace {

using symbolic::Graph;
using symbolic::Node;
using symbolic::NodeId;
using symbolic::Op;

class Scheduler {
 public:
  Scheduler(const Graph& g, const FunctionDefinition& f, const LoweringOptions& o, const std::vector<char>& needed,
            std::uint32_t needed_count)
      : g_(g), f_(f), options_(o), needed_(needed), needed_count_(needed_count), n_(g.size()), out_(g.size()) {}

  StepSchedule run() {
    makeSteps(callsOfInputsFirst());
    if (options_.lane_pairs != LanePairMode::Off) pairSteps();
    assignChunks();
    if (options_.lane_pairs == LanePairMode::Order) splitPairs();
    return std::move(out_);
  }

 private:
  bool isComputed(NodeId id) const {
    const Node& n = g_.node(id);
    NodeId operand;
    return n.op != Op::Constant && n.op != Op::Input && !isNegation(g_, n, &operand);
  }

  // A unary operation that becomes a library call (sin, cos, exp, ...), not an instruction.
  bool isCall(NodeId id) const {
    switch (g_.node(id).op) {
      case Op::Sin: case Op::Cos: case Op::Tan: case Op::Asin: case Op::Acos: case Op::Atan:
      case Op::Exp: case Op::Log: case Op::Tanh: return true;
      default: return false;
    }
  }

  // Transcendental functions of inputs (sin/cos of joint angles) come first: most are
  // library calls (W calls in the SIMD variant) that clobber every register, so values
  // live across them are spilled; computed before anything else, only their own
  // results are live. Measured: a Talos part whose 61 sincos calls were interleaved
  // with the kinematics took gcc 48 s and 820 MB to compile, 1.5 s once hoisted.
  // (sin and cos of one argument are now an inline kernel, which keeps its fallback
  // call for huge arguments: hoisted too.)
  std::vector<NodeId> callsOfInputsFirst() const {
    auto hoisted = [&](NodeId id) { return isCall(id) && g_.node(g_.node(id).args[0]).op == Op::Input; };
    std::vector<NodeId> order;
    order.reserve(needed_count_);
    for (NodeId id = 0; id < n_; ++id)
      if (needed_[id] && hoisted(id)) order.push_back(id);
    for (NodeId id : computeOrder())
      if (needed_[id] && !hoisted(id)) order.push_back(id);
    return order;
  }

  // A step per computed node in `order`; sin and cos of one argument in one step, where
  // the first of them comes.
  void makeSteps(const std::vector<NodeId>& order) {
    std::unordered_map<NodeId, NodeId> sin_of, cos_of;  // argument -> node
    for (NodeId id = 0; id < n_; ++id) {
      if (!needed_[id]) continue;
      const Node& n = g_.node(id);
      if (n.op == Op::Sin) sin_of[n.args[0]] = id;
      if (n.op == Op::Cos) cos_of[n.args[0]] = id;
    }
    std::vector<char> done(n_, 0);
    for (NodeId id : order) {
      if (done[id] || !isComputed(id)) continue;
      const Node& n = g_.node(id);
      Step s{id};
      if (n.op == Op::Sin || n.op == Op::Cos) {
        auto& partners = n.op == Op::Sin ? cos_of : sin_of;
        auto it = partners.find(n.args[0]);
        if (it != partners.end()) {
          s.first = n.op == Op::Sin ? id : it->second;
          s.second = n.op == Op::Sin ? it->second : id;
          done[it->second] = 1;
          ++out_.sincos_pairs;
        }
      }
      done[id] = 1;
      out_.steps.push_back(s);
    }
  }

  // The trace's order, or output by output for a large function (emission_order.hpp).
  std::vector<NodeId> computeOrder() const {
    std::uint32_t operations = 0;
    for (NodeId id = 0; id < n_; ++id) operations += needed_[id] && isComputed(id) ? 1 : 0;
    if (options_.output_order_from > 0 && operations >= options_.output_order_from) return outputConeOrder(g_, f_);
    std::vector<NodeId> trace(n_);
    for (NodeId id = 0; id < n_; ++id) trace[id] = id;
    return trace;
  }

  // Chunks of at most split_threshold operations, in the order of the steps.
  void assignChunks() {
    std::uint32_t ops_in_chunk = 0;
    out_.chunks = 1;
    for (Step& s : out_.steps) {
      const std::uint32_t ops = s.second == kNoPair && s.lane1 == kNoPair ? 1 : 2;
      if (options_.split_threshold > 0 && ops_in_chunk > 0 && ops_in_chunk + ops > options_.split_threshold) {
        ++out_.chunks;
        ops_in_chunk = 0;
      }
      ops_in_chunk += ops;
      s.chunk = out_.chunks - 1;
    }
  }

  // Lane pairs (lane_pairs.hpp), the steps reordered so that each pair is one step. In
  // LanePairMode::Order each pair becomes two steps again once the chunks are cut, so
  // that the code without pairs has the same parts and work buffer as the code with them.
  void pairSteps() {
    const double coverage = f_.lane_pairs == LanePairSeeds::Twins ? kTwinPairCoverage : kLanePairCoverage;
    LanePairMemo* memo = options_.lane_pair_memo;
    if (memo && memo->filled && memo->ready_first_sums == options_.ready_first_sums && memo->graph_size == g_.size() &&
        memo->steps_in == out_.steps) {
      out_.steps = memo->steps_out;
      out_.pairs = memo->pairs;
    } else {
      std::vector<Step> steps_in = memo ? out_.steps : std::vector<Step>();
      out_.pairs = scheduleLanePairs(g_, f_, coverage, kLanePairsBelow, out_.steps);
      if (memo) *memo = LanePairMemo{std::move(steps_in), out_.steps, out_.pairs, options_.ready_first_sums, g_.size(), true};
    }
    if (out_.pairs.count() == 0) return;
    out_.twin.assign(n_, kNoPair);
    for (const Step& s : out_.steps)
      if (s.lane1 != kNoPair) out_.twin[s.first] = s.lane1;
  }

  // Each pair step as two steps, one after the other, in the pair's chunk.
  void splitPairs() {
    std::vector<Step> steps;
    steps.reserve(out_.steps.size() + out_.pairs.count());
    for (const Step& s : out_.steps) {
      steps.push_back(Step{s.first, s.second, kNoPair, s.chunk});
      if (s.lane1 != kNoPair) steps.push_back(Step{s.lane1, kNoPair, kNoPair, s.chunk});
    }
    out_.steps = std::move(steps);
    out_.pairs = LanePairs(n_);
  }


  const Graph& g_;
  const FunctionDefinition& f_;
  const LoweringOptions& options_;
  const std::vector<char>& needed_;
  const std::uint32_t needed_count_;
  const NodeId n_;
  StepSchedule out_;
};

}  // namespace

StepSchedule scheduleSteps(const Graph& graph, const FunctionDefinition& function, const LoweringOptions& options,
                           const std::vector<char>& needed, std::uint32_t needed_count) {
  return Scheduler(graph, function, options, needed, needed_count).run();
}

}  // namespace robodiff::codegen::detail
