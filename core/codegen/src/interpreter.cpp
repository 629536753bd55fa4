#include "robodiff/codegen/interpreter.hpp"

#include <cmath>
#include <cstring>
#include <algorithm>
#include <array>
#include <map>

#include "lowering.hpp"
#include "robodiff/codegen/sincos_kernel.h"

namespace robodiff::codegen {
namespace {

using detail::InstrKind;
using detail::Operand;
using symbolic::Op;
using Code = Interpreter::Code;

Code codeOf(Op op) {
  switch (op) {
    case Op::Neg: return Code::Neg;
    case Op::Sin: return Code::Sin;
    case Op::Cos: return Code::Cos;
    case Op::Tan: return Code::Tan;
    case Op::Asin: return Code::Asin;
    case Op::Acos: return Code::Acos;
    case Op::Atan: return Code::Atan;
    case Op::Exp: return Code::Exp;
    case Op::Log: return Code::Log;
    case Op::Sqrt: return Code::Sqrt;
    case Op::Tanh: return Code::Tanh;
    case Op::Abs: return Code::Abs;
    case Op::Add: return Code::Add;
    case Op::Sub: return Code::Sub;
    case Op::Mul: return Code::Mul;
    case Op::Div: return Code::Div;
    case Op::Atan2: return Code::Atan2;
    case Op::Pow: return Code::Pow;
    case Op::Min: return Code::Min;
    case Op::Max: return Code::Max;
    case Op::SelectPositive: return Code::Select;
    case Op::Constant:
    case Op::Input: break;
  }
  throw std::logic_error("interpreter: not an operation");
}

// Slots: [constants | 3 scratch | the lowered function's locals]. Negated operands fold
// into add/sub (a + -b -> a - b) or, rarely, go through a scratch slot. (Products and
// sums are fused into their readers later, in SSA form: fuseSingleUse.)
class Assembler {
 public:
  explicit Assembler(std::vector<Interpreter::Instruction>& code, std::vector<double>& constants,
                     std::uint32_t locals_base)
      : code_(code), constants_(constants), base_(locals_base) {}

  static constexpr std::uint32_t kScratch = 3;

  void assemble(const detail::Chunk& chunk) {
    for (const detail::Instr& ins : chunk.code) lowered(ins);
  }

 public:
  void lowered(const detail::Instr& ins) {
    switch (ins.kind) {
      case InstrKind::LoadInput:
        emit(Code::Load, local(ins.dst), ins.block, ins.index, 0);
        break;
      case InstrKind::Compute:
        compute(ins);
        break;
      case InstrKind::SinCos:
        emit(Code::SinCos, local(ins.dst), plain(ins.args[0], 0), local(ins.dst2), 0);
        break;
      case InstrKind::StoreOutput: {
        const Operand& o = ins.args[0];
        std::uint32_t src;
        if (o.kind == Operand::Kind::Input) {
          src = scratch(0);
          emit(Code::Load, src, o.block, o.index, 0);
        } else {
          src = o.kind == Operand::Kind::Constant ? constant(o.value) : local(o.slot);
        }
        emit(o.negated ? Code::StoreNeg : Code::Store, 0, ins.block, ins.index, src);
        break;
      }
      case InstrKind::ZeroOutput:
        emit(Code::Zero, 0, ins.block, 0, 0);
        break;
      case InstrKind::LoadTransfer:
      case InstrKind::StoreTransfer:
        throw std::logic_error("interpreter: a split function");
    }
  }

 private:
  std::uint32_t constant(double value) {
    std::uint64_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    auto [it, fresh] = constant_slot_.emplace(bits, static_cast<std::uint32_t>(constants_.size()));
    if (fresh) constants_.push_back(value);
    return it->second;
  }
  std::uint32_t scratch(std::uint32_t i) const { return base_ - kScratch + i; }
  std::uint32_t local(std::uint32_t slot) const { return base_ + slot; }
  // The slot of an operand read without its sign.
  std::uint32_t slotOf(const Operand& o) { return o.kind == Operand::Kind::Constant ? constant(o.value) : local(o.slot); }
  // The slot holding the operand's value, negating into scratch slot i when needed.
  std::uint32_t plain(const Operand& o, std::uint32_t i) {
    if (o.kind != Operand::Kind::Slot || !o.negated) return slotOf(o);
    emit(Code::Neg, scratch(i), local(o.slot), 0, 0);
    return scratch(i);
  }

  void compute(const detail::Instr& ins) {
    const std::uint32_t dst = local(ins.dst);
    const Operand* a = ins.args;
    if (ins.op == Op::Add || ins.op == Op::Sub) {
      const bool nx = a[0].kind == Operand::Kind::Slot && a[0].negated;
      const bool ny = a[1].kind == Operand::Kind::Slot && a[1].negated;
      const std::uint32_t x = slotOf(a[0]), y = slotOf(a[1]);
      const bool add = ins.op == Op::Add;
      if (!nx && !ny) emit(add ? Code::Add : Code::Sub, dst, x, y, 0);
      else if (!nx && ny) emit(add ? Code::Sub : Code::Add, dst, x, y, 0);  // x + -y, x - -y
      else if (nx && ny && !add) emit(Code::Sub, dst, y, x, 0);             // -x - -y = y - x
      else if (nx && !ny && add) emit(Code::Sub, dst, y, x, 0);             // -x + y = y - x
      else emit(Code::Sub, dst, plain(a[0], 0), y, 0);                      // -x - y, -x + -y
      return;
    }
    const int n = symbolic::arity(ins.op);
    std::uint32_t s[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i) s[i] = plain(a[i], static_cast<std::uint32_t>(i));
    emit(codeOf(ins.op), dst, s[0], s[1], s[2]);
  }

  void emit(Code c, std::uint32_t dst, std::uint32_t a, std::uint32_t b, std::uint32_t cc) {
    code_.push_back({c, dst, a, b, cc});
  }

  std::vector<Interpreter::Instruction>& code_;
  std::vector<double>& constants_;
  std::uint32_t base_;
  std::map<std::uint64_t, std::uint32_t> constant_slot_;
};


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

// Scheduling. The assembled program is straight-line code whose slots are reused by
// liveness; dispatch (one indirect, often mispredicted jump per instruction) dominates
// its time. Any order that respects the data flow computes every value with the same
// operations on the same operands, so results are bit-identical; we pick one that puts
// instructions of one opcode together (greedy list scheduling: keep emitting the
// current opcode while any instruction of it is ready, else switch to the opcode with
// the most ready instructions), so that one dispatch runs a tight loop over many
// independent instructions. Slots are then reassigned by liveness in the new order.
struct Node {
  Code code;
  std::uint32_t reads[3], writes[2];
  std::uint32_t block = 0, index = 0;
};

// See step 1b of the constructor. Removes the fused producers from `nodes`.
void fuseSingleUse(std::vector<Node>& nodes, std::uint32_t nconst, std::uint32_t values) {
  std::vector<std::uint32_t> uses(values, 0), producer(values, ~0u);
  for (std::uint32_t k = 0; k < nodes.size(); ++k) {
    const Shape sh = shapeOf(nodes[k].code);
    for (int r = 0; r < sh.reads; ++r) ++uses[nodes[k].reads[r]];
    for (int w = 0; w < sh.writes; ++w) producer[nodes[k].writes[w]] = k;
  }
  std::vector<char> dead(nodes.size(), 0);
  for (Node& n : nodes) {
    if (n.code != Code::Add && n.code != Code::Sub && n.code != Code::Mul) continue;
    // The operand to absorb: produced by a Mul or an Add read only here.
    for (int side = 0; side < 2; ++side) {
      const std::uint32_t x = n.reads[side], other = n.reads[1 - side];
      if (x < nconst || x == other || uses[x] != 1) continue;
      const std::uint32_t pk = producer[x];
      if (pk == ~0u || dead[pk]) continue;
      const Node& p = nodes[pk];
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

}  // namespace

Interpreter::Interpreter(const symbolic::Graph& graph, FunctionDefinition function) : function_(std::move(function)) {
  function_.validate(graph);
  for (const auto& b : function_.inputs) input_sizes_.push_back(b.size);
  for (const auto& b : function_.outputs) output_sizes_.push_back(b.size());
  const detail::LoweredFunction lowered = detail::lower(graph, function_);
  const detail::Chunk& chunk = lowered.chunks.at(0);

  // Constants take the first slots, so their number must be known before the locals'
  // base: assemble against a provisional base, then shift local slot numbers.
  std::vector<Instruction> code;
  std::vector<double> constants;
  constexpr std::uint32_t kProvisional = 1u << 30;
  Assembler assembler(code, constants, kProvisional + Assembler::kScratch);
  assembler.assemble(chunk);
  const std::uint32_t shift = static_cast<std::uint32_t>(constants.size());
  auto fix = [&](std::uint32_t& s) {
    if (s >= kProvisional) s = s - kProvisional + shift;
  };
  for (Instruction& ins : code) {
    switch (ins.code) {
      case Code::Load: fix(ins.dst); break;
      case Code::Store:
      case Code::StoreNeg: fix(ins.c); break;
      case Code::Zero: break;
      case Code::SinCos: fix(ins.dst); fix(ins.a); fix(ins.b); break;
      default: fix(ins.dst); fix(ins.a); fix(ins.b); fix(ins.c); break;
    }
  }
  const std::uint32_t nconst = shift;
  const std::uint32_t nslots = nconst + Assembler::kScratch + chunk.slots;

  // 1. Values (SSA): constants are values 0 .. nconst-1, every write a new value.
  std::vector<Node> nodes(code.size());
  std::vector<std::uint32_t> current(nslots);
  for (std::uint32_t k = 0; k < nslots; ++k) current[k] = k;  // only constants are read unwritten
  std::uint32_t values = nconst;
  for (std::size_t k = 0; k < code.size(); ++k) {
    const Instruction& ins = code[k];
    Node& n = nodes[k];
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

  // 1b. Fusion of values read once: a product or sum whose only reader multiplies or
  // adds it becomes part of that reader (MulMul (a*b)*c, MulAdd, MulSub, SubMul, AddAdd
  // (a+b)+c, AddSub (a+b)-c, SubAdd c-(a+b)). The same operations in the same order,
  // rounded after each, so results stay bit for bit; one dispatch and one stored value
  // less each.
  fuseSingleUse(nodes, nconst, values);

  // 2. Greedy list scheduling by opcode. Zero first (before any store of its block).
  const std::size_t N = nodes.size();
  executed_ = N;
  std::vector<std::uint32_t> waiting(N, 0);  // unscheduled producers still awaited
  std::vector<std::vector<std::uint32_t>> consumers(values - nconst);
  for (std::size_t k = 0; k < N; ++k) {
    const Shape sh = shapeOf(nodes[k].code);
    for (int r = 0; r < sh.reads; ++r) {
      const std::uint32_t x = nodes[k].reads[r];
      if (x < nconst) continue;
      consumers[x - nconst].push_back(static_cast<std::uint32_t>(k));
      ++waiting[k];
    }
  }
  constexpr int kCodes = static_cast<int>(Code::End) + 1;
  std::array<std::vector<std::uint32_t>, kCodes> ready;  // LIFO per opcode
  std::array<std::size_t, kCodes> ready_head{};
  std::vector<std::uint32_t> order;
  order.reserve(N);
  for (std::size_t k = 0; k < N; ++k)
    if (nodes[k].code == Code::Zero) order.push_back(static_cast<std::uint32_t>(k));
  for (std::size_t k = 0; k < N; ++k)
    if (nodes[k].code != Code::Zero && waiting[k] == 0) ready[static_cast<int>(nodes[k].code)].push_back(static_cast<std::uint32_t>(k));
  // Urgency: the most opcode changes on any path from an instruction to the end (the
  // stream is in topological order, so one backward pass). Switching to the opcode of
  // the most urgent ready instruction keeps long chains of alternating opcodes moving:
  // UR5's RNEA Jacobian went from 223 groups (most ready first) to 107.
  std::vector<std::uint32_t> urgency(N, 0);
  for (std::size_t k = N; k-- > 0;) {
    const Shape sh = shapeOf(nodes[k].code);
    for (int w = 0; w < sh.writes; ++w)
      for (std::uint32_t c : consumers[nodes[k].writes[w] - nconst])
        urgency[k] = std::max(urgency[k], urgency[c] + (nodes[c].code != nodes[k].code ? 1u : 0u));
  }
  int cur = -1;
  while (order.size() < N) {
    auto avail = [&](int c) { return ready[c].size() - ready_head[c]; };
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
    const std::uint32_t k = ready[cur][ready_head[cur]++];  // FIFO: original order among ready ones
    order.push_back(k);
    const Shape sh = shapeOf(nodes[k].code);
    for (int w = 0; w < sh.writes; ++w)
      for (std::uint32_t c : consumers[nodes[k].writes[w] - nconst])
        if (--waiting[c] == 0) ready[static_cast<int>(nodes[c].code)].push_back(c);
  }

  // 3. Slots by liveness in the new order.
  std::vector<std::uint32_t> last_use(values - nconst, 0), slot(values - nconst, 0);
  std::vector<char> used(values - nconst, 0);
  for (std::uint32_t p = 0; p < N; ++p) {
    const Node& n = nodes[order[p]];
    const Shape sh = shapeOf(n.code);
    for (int r = 0; r < sh.reads; ++r)
      if (n.reads[r] >= nconst) last_use[n.reads[r] - nconst] = p, used[n.reads[r] - nconst] = 1;
  }
  std::vector<std::uint32_t> free_slots;
  std::uint32_t next_slot = nconst;
  stream_.clear();
  groups_ = 0;
  std::size_t count_at = 0;
  int group_code = -1;
  for (std::uint32_t p = 0; p < N; ++p) {
    const Node& n = nodes[order[p]];
    const Shape sh = shapeOf(n.code);
    std::uint32_t rs[3] = {0, 0, 0}, ws[2] = {0, 0};
    for (int r = 0; r < sh.reads; ++r) rs[r] = n.reads[r] < nconst ? n.reads[r] : slot[n.reads[r] - nconst];
    for (int r = 0; r < sh.reads; ++r) {
      const std::uint32_t x = n.reads[r];
      if (x >= nconst && last_use[x - nconst] == p) {
        last_use[x - nconst] = ~0u;  // freed once even when read twice
        free_slots.push_back(slot[x - nconst]);
      }
    }
    for (int w = 0; w < sh.writes; ++w) {
      std::uint32_t s;
      if (!free_slots.empty()) s = free_slots.back(), free_slots.pop_back();
      else s = next_slot++;
      slot[n.writes[w] - nconst] = ws[w] = s;
    }
    for (int w = 0; w < sh.writes; ++w)
      if (!used[n.writes[w] - nconst]) free_slots.push_back(ws[w]);  // never read
    if (static_cast<int>(n.code) != group_code) {
      group_code = static_cast<int>(n.code);
      stream_.push_back(static_cast<std::uint32_t>(n.code));
      count_at = stream_.size();
      stream_.push_back(0);
      ++groups_;
    }
    ++stream_[count_at];
    for (int w = 0; w < sh.writes; ++w) stream_.push_back(ws[w]);
    for (int r = 0; r < sh.reads; ++r) stream_.push_back(rs[r]);
    if (n.code == Code::Load || n.code == Code::Store || n.code == Code::StoreNeg) {
      stream_.push_back(n.block);
      stream_.push_back(n.index);
    } else if (n.code == Code::Zero) {
      stream_.push_back(n.block);
    }
  }
  stream_.push_back(static_cast<std::uint32_t>(Code::End));
  stream_.push_back(0);
  // The 16-bit stream, when every field and count fits (all but huge functions); three
  // more zeros, so the last entry's 8-byte read stays inside it.
  stream16_.clear();
  if (std::all_of(stream_.begin(), stream_.end(), [](std::uint32_t x) { return x <= 0xffffu; })) {
    stream16_.assign(stream_.begin(), stream_.end());
    stream16_.resize(stream16_.size() + 3, 0);
    stream_.clear();
    stream_.shrink_to_fit();
  }

  code.push_back({Code::End, 0, 0, 0, 0});
  code_ = std::move(code);
  constants_ = std::move(constants);
  work_size_ = next_slot;
}

void Interpreter::evaluate(const double* const* in, double* const* out, double* work) const { run(0, in, out, work); }

void Interpreter::evaluateBatch(std::uint64_t n, const double* const* in, double* const* out, double* work) const {
  for (std::uint64_t k = 0; k < n; ++k) run(k, in, out, work);
}

// Each operation: its stream entry's width (fields) and its effect on the slots v,
// given the entry's fields f (writes, then reads, then block and index).
#define ROBODIFF_INTERPRETER_OPS(OP)                                        \
  OP(Load, 3, v[f[0]] = in[f[1]][knot * in_size[f[1]] + f[2]])              \
  OP(Store, 3, out[f[1]][knot * out_size[f[1]] + f[2]] = v[f[0]])            \
  OP(StoreNeg, 3, out[f[1]][knot * out_size[f[1]] + f[2]] = -v[f[0]])        \
  OP(Zero, 1, std::memset(out[f[0]] + knot * out_size[f[0]], 0, out_size[f[0]] * sizeof(double))) \
  OP(Neg, 2, v[f[0]] = -v[f[1]])                                             \
  OP(Sin, 2, v[f[0]] = std::sin(v[f[1]]))                                    \
  OP(Cos, 2, v[f[0]] = std::cos(v[f[1]]))                                    \
  OP(SinCos, 3, rd_sincos1(v[f[2]], &v[f[0]], &v[f[1]]))  /* as generated code */ \
  OP(Tan, 2, v[f[0]] = std::tan(v[f[1]]))                                    \
  OP(Asin, 2, v[f[0]] = std::asin(v[f[1]]))                                  \
  OP(Acos, 2, v[f[0]] = std::acos(v[f[1]]))                                  \
  OP(Atan, 2, v[f[0]] = std::atan(v[f[1]]))                                  \
  OP(Exp, 2, v[f[0]] = std::exp(v[f[1]]))                                    \
  OP(Log, 2, v[f[0]] = std::log(v[f[1]]))                                    \
  OP(Sqrt, 2, v[f[0]] = std::sqrt(v[f[1]]))                                  \
  OP(Tanh, 2, v[f[0]] = std::tanh(v[f[1]]))                                  \
  OP(Abs, 2, v[f[0]] = std::fabs(v[f[1]]))                                   \
  OP(Add, 3, v[f[0]] = v[f[1]] + v[f[2]])                                    \
  OP(Sub, 3, v[f[0]] = v[f[1]] - v[f[2]])                                    \
  OP(Mul, 3, v[f[0]] = v[f[1]] * v[f[2]])                                    \
  OP(Div, 3, v[f[0]] = v[f[1]] / v[f[2]])                                    \
  OP(Atan2, 3, v[f[0]] = std::atan2(v[f[1]], v[f[2]]))                       \
  OP(Pow, 3, v[f[0]] = std::pow(v[f[1]], v[f[2]]))                           \
  OP(Min, 3, v[f[0]] = std::fmin(v[f[1]], v[f[2]]))                          \
  OP(Max, 3, v[f[0]] = std::fmax(v[f[1]], v[f[2]]))                          \
  OP(Select, 4, v[f[0]] = v[f[1]] > 0 ? v[f[2]] : v[f[3]])                   \
  OP(MulAdd, 4, v[f[0]] = v[f[1]] * v[f[2]] + v[f[3]])                       \
  OP(MulSub, 4, v[f[0]] = v[f[1]] * v[f[2]] - v[f[3]])                       \
  OP(SubMul, 4, v[f[0]] = v[f[3]] - v[f[1]] * v[f[2]])                       \
  OP(MulMul, 4, v[f[0]] = v[f[1]] * v[f[2]] * v[f[3]])                       \
  OP(AddAdd, 4, v[f[0]] = v[f[1]] + v[f[2]] + v[f[3]])                       \
  OP(AddSub, 4, v[f[0]] = v[f[1]] + v[f[2]] - v[f[3]])                       \
  OP(SubAdd, 4, v[f[0]] = v[f[3]] - (v[f[1]] + v[f[2]]))

const char* Interpreter::name(Code code) {
#define ROBODIFF_NAME(name, width, body) #name,
  static const char* const names[] = {ROBODIFF_INTERPRETER_OPS(ROBODIFF_NAME) "End"};
#undef ROBODIFF_NAME
  return names[static_cast<int>(code)];
}

namespace {

// An entry's fields. 32-bit streams read them one by one; 16-bit ones read the whole
// entry (at most 4 fields) with one 8-byte load and shifts, which leaves the loop's
// load slots to the operands (Talos RNEA Jacobian 13.1 -> 11.8 us; functions with
// short groups, bound by the groups' branches, gain little).
template <class Field> struct Fields;
template <> struct Fields<std::uint32_t> {
  const std::uint32_t* e;
  explicit Fields(const std::uint32_t* entry) : e(entry) {}
  std::uint32_t operator[](int k) const { return e[k]; }
};
template <> struct Fields<std::uint16_t> {
  std::uint64_t word;
  explicit Fields(const std::uint16_t* entry) { std::memcpy(&word, entry, sizeof word); }
  std::uint32_t operator[](int k) const { return static_cast<std::uint32_t>((word >> (16 * k)) & 0xffffu); }
};

}  // namespace

void Interpreter::run(std::uint64_t knot, const double* const* in, double* const* out, double* v) const {
  if (!constants_.empty()) std::memcpy(v, constants_.data(), constants_.size() * sizeof(double));
  if (!stream16_.empty()) runStream(stream16_.data(), knot, in, out, v);
  else runStream(stream_.data(), knot, in, out, v);
}

template <class Field>
void Interpreter::runStream(const Field* p, std::uint64_t knot, const double* const* in, double* const* out,
                            double* v) const {
  const std::uint32_t* in_size = input_sizes_.data();
  const std::uint32_t* out_size = output_sizes_.data();
#ifdef __GNUC__
  // Direct threading (GNU computed goto): one indirect jump per group, then a loop
  // over the group's entries. The stream ends with an End group.
#define ROBODIFF_LABEL(name, width, body) &&op_##name,
  static const void* const labels[] = {ROBODIFF_INTERPRETER_OPS(ROBODIFF_LABEL) && op_End};
#undef ROBODIFF_LABEL
  goto* labels[p[0]];
#define ROBODIFF_BODY(name, width, body)                                   \
  op_##name : {                                                            \
    const Field* e = p + 2;                                                \
    const Field* const stop = e + std::size_t{p[1]} * (width);             \
    _Pragma("GCC unroll 4") for (; e != stop; e += (width)) {              \
      const Fields<Field> f(e);                                            \
      body;                                                                \
    }                                                                      \
    p = stop;                                                              \
  }                                                                        \
  goto* labels[p[0]];
  ROBODIFF_INTERPRETER_OPS(ROBODIFF_BODY)
#undef ROBODIFF_BODY
op_End:
  return;
#else
  for (;;) {
    const Field* e = p + 2;
    switch (static_cast<Code>(p[0])) {
#define ROBODIFF_CASE(name, width, body)                                   \
  case Code::name: {                                                       \
    const Field* const stop = e + std::size_t{p[1]} * (width);             \
    for (; e != stop; e += (width)) {                                      \
      const Fields<Field> f(e);                                            \
      body;                                                                \
    }                                                                      \
    p = stop;                                                              \
    break;                                                                 \
  }
      ROBODIFF_INTERPRETER_OPS(ROBODIFF_CASE)
#undef ROBODIFF_CASE
      case Code::End: return;
    }
  }
#endif
}

}  // namespace robodiff::codegen
