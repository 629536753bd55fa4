#include "lowering.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lane_pairs.hpp"
#include "operand_ref.hpp"
#include "step_schedule.hpp"
#include "robodiff/codegen/sincos_kernel.h"
#include "sum_chains.hpp"
#include "transfer_slots.hpp"

namespace robodiff::codegen::detail {
namespace {

using symbolic::Graph;
using symbolic::Node;
using symbolic::Op;

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

struct OutputEntry {
  std::uint32_t block, index;
  bool negated;
  std::uint32_t next;  // next entry of the same node, or kNone
};

class Lowerer {
 public:
  Lowerer(const Graph& g, const FunctionDefinition& f, const LoweringOptions& o)
      : g_(g), f_(f), options_(o), n_(g.size()), pairs_(g.size()) {}

  LoweredFunction run() {
    markNeeded();
    mapInputs();
    collectOutputs();
    schedule();
    assignTransfers();
    LoweredFunction out;
    out.chunks.resize(chunk_count_);
    emitPrologue(out.chunks[0]);
    const std::size_t prologue = out.chunks[0].code.size();
    for (std::uint32_t c = 0; c < chunk_count_; ++c) emitChunk(c, out.chunks[c]);
    storeAfterTheFirstKernel(out.chunks[0], prologue);
    out.transfer_slots = transfer_slots_;
    out.needed_nodes = needed_count_;
    for (const Chunk& c : out.chunks) out.operations += c.operations;
    out.sincos_pairs = sincos_pairs_;
    out.lane_pairs = static_cast<std::uint32_t>(pairs_.count());
    out.sincos_lane_pairs = sincos_lane_pairs_;
    out.sincos_inputs = sincosInputs();
    return out;
  }

 private:
  // The input elements whose sin and cos the kernels compute; empty where any kernel's
  // argument is not an input (nor a constant in the kernel's range).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> sincosInputs() const {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> elements;
    for (const Step& s : steps_) {
      if (s.second == kNone) continue;
      const Ref x = resolve(g_, g_.node(s.first).args[0]);
      if (x.is_constant && std::fabs(x.value) <= RD_SC_LIMIT) continue;
      if (x.is_constant || g_.node(x.base).op != Op::Input) return {};
      elements.push_back(input_where_[g_.node(x.base).index]);
    }
    std::sort(elements.begin(), elements.end());
    elements.erase(std::unique(elements.begin(), elements.end()), elements.end());
    return elements;
  }

  void markNeeded() {
    needed_.assign(n_, 0);
    for (const auto& b : f_.outputs)
      for (NodeId id : b.values) needed_[id] = 1;
    for (std::size_t i = n_; i-- > 0;) {
      if (!needed_[i]) continue;
      ++needed_count_;
      const Node& n = g_.node(static_cast<NodeId>(i));
      for (int a = 0; a < symbolic::arity(n.op); ++a) needed_[n.args[a]] = 1;
    }
  }

  void mapInputs() {
    for (std::uint32_t b = 0; b < f_.inputs.size(); ++b)
      for (std::uint32_t i = 0; i < f_.inputs[b].size; ++i) input_where_.push_back({b, i});
  }

  void collectOutputs() {
    out_head_.assign(n_, kNone);
    for (std::uint32_t b = 0; b < f_.outputs.size(); ++b) {
      const auto& values = f_.outputs[b].values;
      for (std::uint32_t i = values.size(); i-- > 0;) {  // reversed: lists come out in order
        Ref r = resolve(g_, values[i]);
        if (r.is_constant || g_.node(r.base).op == Op::Input) {
          prologue_.push_back({b, i, r});
          continue;
        }
        out_entries_.push_back({b, i, r.negated, out_head_[r.base]});
        out_head_[r.base] = static_cast<std::uint32_t>(out_entries_.size() - 1);
      }
    }
    std::reverse(prologue_.begin(), prologue_.end());
  }

  // The steps, their chunks and lane pairs (step_schedule.hpp).
  void schedule() {
    StepSchedule s = scheduleSteps(g_, f_, options_, needed_, needed_count_);
    steps_ = std::move(s.steps);
    chunk_count_ = s.chunks;
    sincos_pairs_ = s.sincos_pairs;
    pairs_ = std::move(s.pairs);
    twin_ = std::move(s.twin);
  }

  void assignTransfers() {
    TransferSlots slots = assignTransferSlots(g_, steps_, twin_, chunk_count_);
    transfer_slot_ = std::move(slots.slot);
    transfer_slots_ = slots.count;
  }

  // Blocks with at least this many constant-zero entries have them cleared by one
  // ZeroOutput (with the runs of zeros, for the C emitter to choose how): thousands of
  // single stores (a Talos Jacobian has ~2,500 zeros) cost the compiler far more than a
  // memset costs at run time.
  static constexpr std::uint32_t kZeroBlockMinimum = 16;

  static bool isZero(const Ref& r) { return r.is_constant && r.value == 0.0 && !std::signbit(r.value); }

  // The prologue's output stores (zeros, constants, copied inputs) moved to just after
  // the first sin-cos kernel where nothing is stored before it. The kernels' arguments
  // are then loaded before any store, so none of those loads waits on an earlier store
  // whose address matches it in the low 12 bits (4K aliasing: the free-flying Talos's
  // frame Jacobian took 35 ns instead of 21 with its input and output so placed), and
  // the stores issue while the kernel runs (docs/code-generation.md).
  static void storeAfterTheFirstKernel(Chunk& chunk, std::size_t prologue) {
    std::vector<Instr>& code = chunk.code;
    for (std::size_t i = prologue; i < code.size(); ++i) {
      const InstrKind k = code[i].kind;
      if (k == InstrKind::StoreOutput || k == InstrKind::ZeroOutput) return;
      if (k == InstrKind::SinCos || k == InstrKind::SinCosPair || k == InstrKind::SinCosQuad) {
        std::rotate(code.begin(), code.begin() + static_cast<std::ptrdiff_t>(prologue),
                    code.begin() + static_cast<std::ptrdiff_t>(i + 1));
        return;
      }
    }
  }

  void emitPrologue(Chunk& chunk) {
    std::vector<std::vector<ZeroRun>> runs(f_.outputs.size());
    std::vector<std::uint32_t> zeros(f_.outputs.size(), 0);
    for (const auto& p : prologue_) {  // in order of block and index
      if (!isZero(p.ref)) continue;
      ++zeros[p.block];
      std::vector<ZeroRun>& r = runs[p.block];
      if (!r.empty() && r.back().start + r.back().length == p.index) ++r.back().length;
      else r.push_back({p.index, 1});
    }
    for (std::uint32_t b = 0; b < zeros.size(); ++b)
      if (zeros[b] >= kZeroBlockMinimum) {
        Instr ins;
        ins.kind = InstrKind::ZeroOutput;
        ins.block = b;
        ins.index = static_cast<std::uint32_t>(chunk.zero_runs.size());
        chunk.zero_runs.push_back(std::move(runs[b]));
        chunk.code.push_back(ins);
      }
    for (const auto& p : prologue_) {
      if (isZero(p.ref) && zeros[p.block] >= kZeroBlockMinimum) continue;
      Instr ins;
      ins.kind = InstrKind::StoreOutput;
      ins.block = p.block;
      ins.index = p.index;
      if (p.ref.is_constant) {
        ins.args[0].kind = Operand::Kind::Constant;
        ins.args[0].value = p.ref.value;
      } else {
        auto [b, i] = input_where_[g_.node(p.ref.base).index];
        ins.args[0].kind = Operand::Kind::Input;
        ins.args[0].block = b;
        ins.args[0].index = i;
        ins.args[0].negated = p.ref.negated;
      }
      chunk.code.push_back(ins);
    }
  }

  std::uint32_t allocate() {
    if (options_.reuse_slots && !free_.empty()) {
      std::uint32_t s = free_.back();
      free_.pop_back();
      return s;
    }
    return next_slot_++;
  }
  void release(std::uint32_t slot) {
    if (options_.reuse_slots) free_.push_back(slot);
  }

  void emitChunk(std::uint32_t c, Chunk& chunk) {
    if (last_read_.empty()) {
      last_read_.assign(n_, kNone);
      last_read_chunk_.assign(n_, kNone);
      local_chunk_.assign(n_, kNone);
      local_slot_.assign(n_, 0);
      local_lane_.assign(n_, kScalar);
      computed_early_.assign(n_, 0);
    }
    free_.clear();
    free_pairs_.clear();
    next_slot_ = 0;
    next_pair_slot_ = 0;
    auto begin = std::lower_bound(steps_.begin(), steps_.end(), c, [](const Step& s, std::uint32_t v) { return s.chunk < v; });
    auto end = std::upper_bound(begin, steps_.end(), c, [](std::uint32_t v, const Step& s) { return v < s.chunk; });
    // Last position (step offset) in this chunk where each value is read.
    for (auto it = begin; it != end; ++it)
      for (NodeId id : {it->first, it->lane1}) {
        if (id == kNone) continue;
        const Node& n = g_.node(id);
        for (int a = 0; a < symbolic::arity(n.op); ++a) {
          Ref r = resolve(g_, n.args[a]);
          if (r.is_constant) continue;
          last_read_[r.base] = static_cast<std::uint32_t>(it - begin);
          last_read_chunk_[r.base] = c;
        }
      }
    chunk_ = c;
    for (auto it = begin; it != end; ++it) {
      const std::uint32_t pos = static_cast<std::uint32_t>(it - begin);
      if (computed_early_[it->first]) {  // a sin and cos computed with an earlier pair's
        releaseDying(pos, {it->first});
        continue;
      }
      if (it->second != kNone && emitSinCosLanes(pos, it, end, chunk)) continue;
      if (it->lane1 == kNone) emitStep(pos, *it, chunk);
      else emitPairStep(pos, *it, chunk);
    }
    chunk.slots = next_slot_;
    chunk.pair_slots = next_pair_slot_;
  }

  std::uint32_t lastRead(NodeId id) const { return last_read_chunk_[id] == chunk_ ? last_read_[id] : kNone; }

  // An operand as a scalar read: a constant, a local, or a lane of a pair local (loaded
  // first from the inputs or the work buffer if this chunk has not seen it yet).
  Operand scalarOperand(const Ref& r, Chunk& chunk) {
    Operand o;
    if (r.is_constant) {
      o.kind = Operand::Kind::Constant;
      o.value = r.value;
      return o;
    }
    if (local_chunk_[r.base] != chunk_) load(chunk_, r.base, chunk);
    o = localOperand(r.base);
    o.negated = r.negated;
    return o;
  }
  Operand localOperand(NodeId id) const {
    Operand o;
    o.slot = local_slot_[id];
    if (local_lane_[id] != kScalar) {
      o.kind = Operand::Kind::Lane;
      o.lane = local_lane_[id];
    }
    return o;
  }

  // Values whose last reader is the step at `pos` give up their locals.
  void releaseDying(std::uint32_t pos, std::initializer_list<NodeId> readers) {
    NodeId dying[6];
    int n_dying = 0;
    for (NodeId id : readers) {
      if (id == kNone) continue;
      const Node& n = g_.node(id);
      for (int a = 0; a < symbolic::arity(n.op); ++a) {
        Ref r = resolve(g_, n.args[a]);
        if (!r.is_constant && lastRead(r.base) == pos && std::find(dying, dying + n_dying, r.base) == dying + n_dying)
          dying[n_dying++] = r.base;
      }
    }
    for (int d = 0; d < n_dying; ++d) kill(dying[d]);
  }
  void kill(NodeId id) {
    if (local_lane_[id] == kScalar) release(local_slot_[id]);
    else if (--pair_live_[local_slot_[id]] == 0) releasePair(local_slot_[id]);
  }

  void emitStep(std::uint32_t pos, const Step& step, Chunk& chunk) {
    const Node& n = g_.node(step.first);
    Instr ins;
    ins.kind = step.second == kNone ? InstrKind::Compute : InstrKind::SinCos;
    ins.op = n.op;
    for (int a = 0; a < symbolic::arity(n.op); ++a) ins.args[a] = scalarOperand(resolve(g_, n.args[a]), chunk);
    releaseDying(pos, {step.first});
    ins.dst = define(chunk_, step.first);
    if (step.second != kNone) ins.dst2 = define(chunk_, step.second);
    chunk.code.push_back(ins);
    ++chunk.operations;
    for (NodeId d : {step.first, step.second}) {
      if (d == kNone) continue;
      afterDefinition(d, chunk);
      if (lastRead(d) == kNone) kill(d);  // no later reader in this chunk: dead at once
    }
  }

  // Two isomorphic operations in the lanes of one pair local. An operand already in a
  // pair local's lanes in this order is read as it is; any other is packed first.
  void emitPairStep(std::uint32_t pos, const Step& step, Chunk& chunk) {
    const NodeId a = step.first, b = step.lane1;
    const bool swapped = pairs_.swapped(b);
    Instr ins;
    ins.kind = InstrKind::ComputePair;
    ins.op = g_.node(a).op;
    std::uint32_t packed[3];
    int n_packed = 0;
    for (int k = 0; k < symbolic::arity(ins.op); ++k) {
      const Ref x = resolve(g_, g_.node(a).args[k]);
      const Ref y = resolve(g_, g_.node(b).args[swapped ? 1 - k : k]);
      Operand& o = ins.args[k];
      o.kind = Operand::Kind::Pair;
      loadTransferredPair(x, y, chunk);
      if (inLanes(x, y)) {
        o.slot = local_slot_[x.base];
        o.negated = x.negated;
        continue;
      }
      Instr pack;
      pack.kind = InstrKind::PackPair;
      pack.args[0] = scalarOperand(x, chunk);
      pack.args[1] = scalarOperand(y, chunk);
      pack.dst = o.slot = allocatePair();
      packed[n_packed++] = pack.dst;
      chunk.code.push_back(pack);
    }
    releaseDying(pos, {a, b});
    for (int p = 0; p < n_packed; ++p) releasePair(packed[p]);
    ins.dst = allocatePair();
    pair_live_[ins.dst] = 2;
    for (NodeId d : {a, b}) {
      local_chunk_[d] = chunk_;
      local_slot_[d] = ins.dst;
      local_lane_[d] = d == a ? 0 : 1;
    }
    chunk.code.push_back(ins);
    chunk.operations += 2;
    const bool together = transfer_slot_[a] != kNone && transfer_slot_[b] == transfer_slot_[a] + 1;
    if (together) {
      Instr st;
      st.kind = InstrKind::StoreTransferPair;
      st.index = transfer_slot_[a];
      st.args[0].kind = Operand::Kind::Pair;
      st.args[0].slot = ins.dst;
      chunk.code.push_back(st);
    }
    for (NodeId d : {a, b}) {
      afterDefinition(d, chunk, !together);
      if (lastRead(d) == kNone) kill(d);
    }
  }

  // With lane pairs (LanePairMode::Emit), sin and cos of two to four arguments run in
  // the lanes of one kernel call (rd_sincos_pair; rd_sincos_quad, 256 bits, for 3 or 4):
  // a step's sin and cos and those of the next sin-cos steps of the chunk whose
  // arguments can be read now (an input, or a value of this chunk already computed).
  // The kernel is ~35 instructions whatever the lanes.
  template <class It> It laterSinCos(It it, It end) const {
    if (options_.lane_pairs != LanePairMode::Emit || !options_.sincos_lanes) return end;
    for (It later = it + 1; later != end; ++later) {
      if (later->second == kNone || later->lane1 != kNone || computed_early_[later->first]) continue;
      const Ref x = resolve(g_, g_.node(later->first).args[0]);
      if (x.is_constant || g_.node(x.base).op == Op::Input || local_chunk_[x.base] == chunk_) return later;
    }
    return end;
  }
  // False: no partner, nothing emitted.
  template <class It> bool emitSinCosLanes(std::uint32_t pos, It it, It end, Chunk& chunk) {
    const Step* steps[4] = {&*it};
    std::size_t n = 1;
    for (It later = laterSinCos(it, end); later != end && n < 4; later = laterSinCos(later, end)) steps[n++] = &*later;
    if (n == 1) return false;
    const std::size_t packs = (n + 1) / 2;  // three angles: the quad's fourth lane repeats the third
    Instr ins;
    ins.kind = packs == 1 ? InstrKind::SinCosPair : InstrKind::SinCosQuad;
    for (std::size_t p = 0; p < packs; ++p) {  // the arguments packed two by two
      Instr pack;
      pack.kind = InstrKind::PackPair;
      for (std::size_t l = 0; l < 2; ++l)
        pack.args[l] = scalarOperand(resolve(g_, g_.node(steps[std::min(2 * p + l, n - 1)]->first).args[0]), chunk);
      pack.dst = allocatePair();
      chunk.code.push_back(pack);
      ins.args[p].kind = Operand::Kind::Pair;
      ins.args[p].slot = pack.dst;
    }
    releaseDying(pos, {it->first});
    for (std::size_t p = 0; p < packs; ++p) releasePair(ins.args[p].slot);
    std::uint32_t* results[4] = {&ins.dst, &ins.dst2, &ins.dst3, &ins.dst4};  // sin, cos of each pack
    for (std::size_t r = 0; r < 2 * packs; ++r) *results[r] = allocatePair();
    for (std::size_t r = 0; r < 2 * packs; ++r) {
      const bool repeated_lane = n % 2 == 1 && r / 2 == packs - 1;  // three angles: lane 1 is never read
      pair_live_[*results[r]] = repeated_lane ? 1 : 2;
    }
    chunk.code.push_back(ins);
    chunk.operations += static_cast<std::uint32_t>(n);
    ++sincos_lane_pairs_;
    for (std::size_t k = 0; k < n; ++k) {
      if (k > 0) computed_early_[steps[k]->first] = 1;
      const NodeId defined[2] = {steps[k]->first, steps[k]->second};  // sin, cos
      for (int f = 0; f < 2; ++f) {
        local_chunk_[defined[f]] = chunk_;
        local_slot_[defined[f]] = *results[2 * (k / 2) + f];
        local_lane_[defined[f]] = static_cast<std::uint8_t>(k % 2);
      }
    }
    for (std::size_t k = 0; k < n; ++k)
      for (NodeId d : {steps[k]->first, steps[k]->second}) {
        afterDefinition(d, chunk);
        if (lastRead(d) == kNone) kill(d);
      }
    return true;
  }

  // Two values handed over by earlier chunks in adjacent slots, x first: loaded at once
  // into the lanes of one pair local.
  void loadTransferredPair(const Ref& x, const Ref& y, Chunk& chunk) {
    if (x.is_constant || y.is_constant || x.negated != y.negated || x.base == y.base) return;
    if (local_chunk_[x.base] == chunk_ || local_chunk_[y.base] == chunk_) return;
    const std::uint32_t slot = transfer_slot_[x.base];
    if (slot == kNone || transfer_slot_[y.base] != slot + 1 || g_.node(x.base).op == Op::Input) return;
    Instr load;
    load.kind = InstrKind::LoadTransferPair;
    load.index = slot;
    load.dst = allocatePair();
    pair_live_[load.dst] = 2;
    for (NodeId d : {x.base, y.base}) {
      local_chunk_[d] = chunk_;
      local_slot_[d] = load.dst;
      local_lane_[d] = d == x.base ? 0 : 1;
    }
    chunk.code.push_back(load);
  }

  // x in lane 0 and y in lane 1 of one pair local of this chunk, with one sign.
  bool inLanes(const Ref& x, const Ref& y) const {
    if (x.is_constant || y.is_constant || x.negated != y.negated || x.base == y.base) return false;
    return local_chunk_[x.base] == chunk_ && local_chunk_[y.base] == chunk_ && local_lane_[x.base] == 0 &&
           local_lane_[y.base] == 1 && local_slot_[x.base] == local_slot_[y.base];
  }

  std::uint32_t allocatePair() {
    if (options_.reuse_slots && !free_pairs_.empty()) {
      std::uint32_t s = free_pairs_.back();
      free_pairs_.pop_back();
      return s;
    }
    if (next_pair_slot_ >= pair_live_.size()) pair_live_.resize(next_pair_slot_ + 1, 0);
    return next_pair_slot_++;
  }
  void releasePair(std::uint32_t slot) {
    if (options_.reuse_slots) free_pairs_.push_back(slot);
  }

  std::uint32_t define(std::uint32_t c, NodeId id) {
    local_chunk_[id] = c;
    local_slot_[id] = allocate();
    local_lane_[id] = kScalar;
    return local_slot_[id];
  }

  void load(std::uint32_t c, NodeId base, Chunk& chunk) {
    Instr ins;
    const Node& n = g_.node(base);
    if (n.op == Op::Input) {
      ins.kind = InstrKind::LoadInput;
      auto [b, i] = input_where_[n.index];
      ins.block = b;
      ins.index = i;
    } else {
      ins.kind = InstrKind::LoadTransfer;
      ins.index = transfer_slot_[base];
    }
    ins.dst = define(c, base);
    chunk.code.push_back(ins);
  }

  // Outputs of a value are written, and a value read by a later chunk handed over,
  // right after it is computed.
  void afterDefinition(NodeId d, Chunk& chunk, bool hand_over = true) {
    for (std::uint32_t e = out_head_[d]; e != kNone; e = out_entries_[e].next) {
      Instr st;
      st.kind = InstrKind::StoreOutput;
      st.block = out_entries_[e].block;
      st.index = out_entries_[e].index;
      st.args[0] = localOperand(d);
      st.args[0].negated = out_entries_[e].negated;
      chunk.code.push_back(st);
    }
    if (hand_over && transfer_slot_[d] != kNone) {
      Instr st;
      st.kind = InstrKind::StoreTransfer;
      st.index = transfer_slot_[d];
      st.args[0] = localOperand(d);
      chunk.code.push_back(st);
    }
  }

  const Graph& g_;
  const FunctionDefinition& f_;
  LoweringOptions options_;
  std::size_t n_;

  std::vector<char> needed_;
  std::uint32_t needed_count_ = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> input_where_;  // flat input -> (block, index)
  struct PrologueEntry {
    std::uint32_t block, index;
    Ref ref;
  };
  std::vector<PrologueEntry> prologue_;  // outputs that are constants or (negated) inputs
  std::vector<OutputEntry> out_entries_;
  std::vector<std::uint32_t> out_head_;

  std::vector<Step> steps_;
  std::uint32_t chunk_count_ = 1;
  std::uint32_t sincos_pairs_ = 0;
  std::vector<std::uint32_t> transfer_slot_;
  std::vector<NodeId> twin_;  // a lane pair's lane-0 node -> its lane-1 node (kNone: none)
  std::vector<char> computed_early_;  // sin nodes of steps computed with an earlier step's
  std::uint32_t sincos_lane_pairs_ = 0;
  std::uint32_t transfer_slots_ = 0;

  LanePairs pairs_;

  // Per chunk being emitted.
  static constexpr std::uint8_t kScalar = 2;  // local_lane_: a scalar local, not a lane
  std::uint32_t chunk_ = 0;
  std::vector<std::uint32_t> last_read_, last_read_chunk_, local_chunk_, local_slot_;
  std::vector<std::uint8_t> local_lane_;
  std::vector<std::uint32_t> free_, free_pairs_, pair_live_;
  std::uint32_t next_slot_ = 0, next_pair_slot_ = 0;
};

}  // namespace

LoweredFunction lower(const Graph& graph, const FunctionDefinition& function, const LoweringOptions& options) {
  if (!options.chain_sums) return Lowerer(graph, function, options).run();
  const ChainedFunction chained = chainSums(graph, function, options.ready_first_sums);
  return Lowerer(chained.graph, chained.function, options).run();
}

bool readyFirstSums(const Graph& graph, const FunctionDefinition& function, LanePairMemo* memo) {
  LoweringOptions paired;
  paired.lane_pairs = LanePairMode::Emit;
  paired.lane_pair_memo = memo;
  return lower(graph, function, paired).lane_pairs == 0;
}

FunctionPairing pairingOf(const Graph& graph, const FunctionDefinition& function) {
  FunctionPairing p;
  p.ready_first_sums = readyFirstSums(graph, function, &p.memo);
  return p;
}

}  // namespace robodiff::codegen::detail
