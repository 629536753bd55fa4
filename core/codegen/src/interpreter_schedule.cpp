#include "interpreter_schedule.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>

namespace robodiff::codegen::detail {
namespace {

using Code = Interpreter::Code;

// What an instruction reads and writes, in slots. Entries of the scheduled stream
// list these fields in this order: writes first, then reads, then block/index.
struct Shape {
  int reads = 0, writes = 0;
};

Shape shapeOf(Code c) {
  switch (c) {
    case Code::Load: return {0, 1};
    case Code::Store:
    case Code::StoreNeg: return {1, 0};
    case Code::Zero:
    case Code::End: return {0, 0};
    case Code::SinCos: return {1, 2};
    case Code::Neg: case Code::Sin: case Code::Cos: case Code::Tan: case Code::Asin: case Code::Acos:
    case Code::Atan: case Code::Exp: case Code::Log: case Code::Sqrt: case Code::Tanh: case Code::Abs:
      return {1, 1};
    case Code::Select: case Code::MulAdd: case Code::MulSub: case Code::SubMul: case Code::MulMul:
    case Code::AddAdd: case Code::AddSub: case Code::SubAdd: return {3, 1};
    default: return {2, 1};
  }
}

// One instruction in value (SSA) form.
struct SsaNode {
  Code code;
  std::uint32_t reads[3], writes[2];
  std::uint32_t block = 0, index = 0;
};

// Fusion of values read once: a product or sum whose only reader multiplies or adds it
// becomes part of that reader (MulMul (a*b)*c, MulAdd, MulSub, SubMul, AddAdd (a+b)+c,
// AddSub (a+b)-c, SubAdd c-(a+b)). The same operations in the same order, rounded after
// each, so results stay bit for bit; one dispatch and one stored value less each.
// Removes the fused producers from `nodes`.
void fuseSingleUse(std::vector<SsaNode>& nodes, std::uint32_t nconst, std::uint32_t values) {
  std::vector<std::uint32_t> uses(values, 0), producer(values, ~0u);
  for (std::uint32_t k = 0; k < nodes.size(); ++k) {
    const Shape sh = shapeOf(nodes[k].code);
    for (int r = 0; r < sh.reads; ++r) ++uses[nodes[k].reads[r]];
    for (int w = 0; w < sh.writes; ++w) producer[nodes[k].writes[w]] = k;
  }
  std::vector<char> dead(nodes.size(), 0);
  for (SsaNode& n : nodes) {
    if (n.code != Code::Add && n.code != Code::Sub && n.code != Code::Mul) continue;
    // The operand to absorb: produced by a Mul or an Add read only here.
    for (int side = 0; side < 2; ++side) {
      const std::uint32_t x = n.reads[side], other = n.reads[1 - side];
      if (x < nconst || x == other || uses[x] != 1) continue;
      const std::uint32_t pk = producer[x];
      if (pk == ~0u || dead[pk]) continue;
      const SsaNode& p = nodes[pk];
      Code fused = Code::End;
      if (p.code == Code::Mul) {
        if (n.code == Code::Mul) fused = Code::MulMul;                        // (a*b)*c, c*(a*b)
        else if (n.code == Code::Add) fused = Code::MulAdd;                   // a*b + c, c + a*b
        else fused = side == 0 ? Code::MulSub : Code::SubMul;                 // a*b - c, c - a*b
      } else if (p.code == Code::Add) {
        if (n.code == Code::Add) fused = Code::AddAdd;                        // (a+b) + c, c + (a+b)
        else if (n.code == Code::Sub) fused = side == 0 ? Code::AddSub : Code::SubAdd;  // (a+b) - c, c - (a+b)
      }
      if (fused == Code::End) continue;
      n.code = fused;
      n.reads[0] = p.reads[0];
      n.reads[1] = p.reads[1];
      n.reads[2] = other;
      dead[pk] = 1;
      break;
    }
  }
  std::size_t kept = 0;
  for (std::size_t k = 0; k < nodes.size(); ++k)
    if (!dead[k]) nodes[kept++] = nodes[k];
  nodes.resize(kept);
}

// Values (SSA): constants are values 0 .. nconst-1, every write a new value. `values`
// returns the number of values.
std::vector<SsaNode> toValues(const std::vector<Interpreter::Instruction>& code, std::uint32_t nconst,
                           std::uint32_t nslots, std::uint32_t& values) {
  std::vector<SsaNode> nodes(code.size());
  std::vector<std::uint32_t> current(nslots);
  for (std::uint32_t k = 0; k < nslots; ++k) current[k] = k;  // only constants are read unwritten
  values = nconst;
  for (std::size_t k = 0; k < code.size(); ++k) {
    const Interpreter::Instruction& ins = code[k];
    SsaNode& n = nodes[k];
    n.code = ins.code;
    const Shape sh = shapeOf(ins.code);
    switch (ins.code) {
      case Code::Load: n.block = ins.a; n.index = ins.b; break;
      case Code::Store:
      case Code::StoreNeg: n.block = ins.a; n.index = ins.b; n.reads[0] = current[ins.c]; break;
      case Code::Zero: n.block = ins.a; break;
      default: {
        const std::uint32_t src[3] = {ins.a, ins.b, ins.c};
        for (int r = 0; r < sh.reads; ++r) n.reads[r] = current[src[r]];
      }
    }
    const std::uint32_t dst[2] = {ins.dst, ins.b};
    for (int w = 0; w < sh.writes; ++w) {
      n.writes[w] = values++;
      current[dst[w]] = n.writes[w];
    }
  }
  return nodes;
}

// The instructions that read each value (indexed value - nconst).
std::vector<std::vector<std::uint32_t>> consumersOf(const std::vector<SsaNode>& nodes, std::uint32_t nconst,
                                                    std::uint32_t values) {
  std::vector<std::vector<std::uint32_t>> consumers(values - nconst);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const Shape sh = shapeOf(nodes[k].code);
    for (int r = 0; r < sh.reads; ++r)
      if (nodes[k].reads[r] >= nconst) consumers[nodes[k].reads[r] - nconst].push_back(static_cast<std::uint32_t>(k));
  }
  return consumers;
}

// Urgency: the most opcode changes on any path from an instruction to the end (the stream
// is in topological order, so one backward pass). Switching to the opcode of the most
// urgent ready instruction keeps long chains of alternating opcodes moving (UR5's RNEA
// Jacobian: 223 groups when the opcode with the most ready instructions is taken, 107 so).
std::vector<std::uint32_t> urgencies(const std::vector<SsaNode>& nodes,
                                     const std::vector<std::vector<std::uint32_t>>& consumers, std::uint32_t nconst) {
  std::vector<std::uint32_t> urgency(nodes.size(), 0);
  for (std::size_t k = nodes.size(); k-- > 0;) {
    const Shape sh = shapeOf(nodes[k].code);
    for (int w = 0; w < sh.writes; ++w)
      for (std::uint32_t c : consumers[nodes[k].writes[w] - nconst])
        urgency[k] = std::max(urgency[k], urgency[c] + (nodes[c].code != nodes[k].code ? 1u : 0u));
  }
  return urgency;
}

// Greedy list scheduling by opcode: keep emitting the current opcode while any
// instruction of it is ready, else switch to the opcode of the most urgent ready one.
// Zero first (before any store of its block). Returns the order (indices into nodes).
std::vector<std::uint32_t> scheduleByOpcode(const std::vector<SsaNode>& nodes, std::uint32_t nconst,
                                            std::uint32_t values) {
  const std::size_t N = nodes.size();
  const std::vector<std::vector<std::uint32_t>> consumers = consumersOf(nodes, nconst, values);
  std::vector<std::uint32_t> waiting(N, 0);  // unscheduled producers still awaited
  for (const auto& readers : consumers)
    for (std::uint32_t k : readers) ++waiting[k];
  constexpr int kCodes = static_cast<int>(Code::End) + 1;
  std::array<std::vector<std::uint32_t>, kCodes> ready;  // FIFO per opcode: original order among ready ones
  std::array<std::size_t, kCodes> ready_head{};
  std::vector<std::uint32_t> order;
  order.reserve(N);
  for (std::size_t k = 0; k < N; ++k)
    if (nodes[k].code == Code::Zero) order.push_back(static_cast<std::uint32_t>(k));
  for (std::size_t k = 0; k < N; ++k)
    if (nodes[k].code != Code::Zero && waiting[k] == 0)
      ready[static_cast<int>(nodes[k].code)].push_back(static_cast<std::uint32_t>(k));
  const std::vector<std::uint32_t> urgency = urgencies(nodes, consumers, nconst);
  auto avail = [&](int c) { return ready[c].size() - ready_head[c]; };
  int cur = -1;
  while (order.size() < N) {
    if (cur < 0 || avail(cur) == 0) {
      cur = -1;
      std::uint32_t best_urgency = 0;
      for (int c = 0; c < kCodes; ++c) {
        if (avail(c) == 0) continue;
        std::uint32_t u = 0;
        for (std::size_t i = ready_head[c]; i < ready[c].size(); ++i) u = std::max(u, urgency[ready[c][i]]);
        if (cur < 0 || u > best_urgency || (u == best_urgency && avail(c) > avail(cur))) cur = c, best_urgency = u;
      }
      if (cur < 0) throw std::logic_error("interpreter: a cycle");
    }
    const std::uint32_t k = ready[cur][ready_head[cur]++];
    order.push_back(k);
    const Shape sh = shapeOf(nodes[k].code);
    for (int w = 0; w < sh.writes; ++w)
      for (std::uint32_t c : consumers[nodes[k].writes[w] - nconst])
        if (--waiting[c] == 0) ready[static_cast<int>(nodes[c].code)].push_back(c);
  }
  return order;
}

// Writes the stream in `order`, giving each value a slot by liveness (a slot is free
// again after its value's last read).
class StreamWriter {
 public:
  StreamWriter(const std::vector<SsaNode>& nodes, const std::vector<std::uint32_t>& order, std::uint32_t nconst,
               std::uint32_t values)
      : nodes_(nodes), order_(order), nconst_(nconst), last_use_(values - nconst, 0), slot_(values - nconst, 0),
        used_(values - nconst, 0), next_slot_(nconst) {
    for (std::uint32_t p = 0; p < order.size(); ++p) {
      const SsaNode& n = nodes[order[p]];
      const Shape sh = shapeOf(n.code);
      for (int r = 0; r < sh.reads; ++r)
        if (n.reads[r] >= nconst) last_use_[n.reads[r] - nconst] = p, used_[n.reads[r] - nconst] = 1;
    }
  }

  ScheduledStream write() {
    for (std::uint32_t p = 0; p < order_.size(); ++p) entry(p);
    out_.stream.push_back(static_cast<std::uint32_t>(Code::End));
    out_.stream.push_back(0);
    out_.executed = order_.size();
    out_.work_size = next_slot_;
    return std::move(out_);
  }

 private:
  void entry(std::uint32_t p) {
    const SsaNode& n = nodes_[order_[p]];
    const Shape sh = shapeOf(n.code);
    std::uint32_t rs[3] = {0, 0, 0}, ws[2] = {0, 0};
    for (int r = 0; r < sh.reads; ++r) rs[r] = n.reads[r] < nconst_ ? n.reads[r] : slot_[n.reads[r] - nconst_];
    for (int r = 0; r < sh.reads; ++r) {
      const std::uint32_t x = n.reads[r];
      if (x >= nconst_ && last_use_[x - nconst_] == p) {
        last_use_[x - nconst_] = ~0u;  // freed once even when read twice
        free_slots_.push_back(slot_[x - nconst_]);
      }
    }
    for (int w = 0; w < sh.writes; ++w) {
      std::uint32_t s;
      if (!free_slots_.empty()) s = free_slots_.back(), free_slots_.pop_back();
      else s = next_slot_++;
      slot_[n.writes[w] - nconst_] = ws[w] = s;
    }
    for (int w = 0; w < sh.writes; ++w)
      if (!used_[n.writes[w] - nconst_]) free_slots_.push_back(ws[w]);  // never read
    std::vector<std::uint32_t>& stream = out_.stream;
    if (static_cast<int>(n.code) != group_code_) {
      group_code_ = static_cast<int>(n.code);
      stream.push_back(static_cast<std::uint32_t>(n.code));
      count_at_ = stream.size();
      stream.push_back(0);
      ++out_.groups;
    }
    ++stream[count_at_];
    for (int w = 0; w < sh.writes; ++w) stream.push_back(ws[w]);
    for (int r = 0; r < sh.reads; ++r) stream.push_back(rs[r]);
    if (n.code == Code::Load || n.code == Code::Store || n.code == Code::StoreNeg) {
      stream.push_back(n.block);
      stream.push_back(n.index);
    } else if (n.code == Code::Zero) {
      stream.push_back(n.block);
    }
  }

  const std::vector<SsaNode>& nodes_;
  const std::vector<std::uint32_t>& order_;
  const std::uint32_t nconst_;
  std::vector<std::uint32_t> last_use_, slot_;
  std::vector<char> used_;
  std::vector<std::uint32_t> free_slots_;
  std::uint32_t next_slot_;
  int group_code_ = -1;
  std::size_t count_at_ = 0;
  ScheduledStream out_;
};

}  // namespace

ScheduledStream scheduleInstructions(const std::vector<Interpreter::Instruction>& code, std::uint32_t nconst,
                                     std::uint32_t nslots) {
  std::uint32_t values = 0;
  std::vector<SsaNode> nodes = toValues(code, nconst, nslots, values);
  fuseSingleUse(nodes, nconst, values);
  const std::vector<std::uint32_t> order = scheduleByOpcode(nodes, nconst, values);
  return StreamWriter(nodes, order, nconst, values).write();
}

}  // namespace robodiff::codegen::detail
