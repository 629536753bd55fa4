#include "robodiff/codegen/interpreter.hpp"

#include <cmath>
#include <cstring>
#include <array>
#include <map>

#include "lowering.hpp"

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

// For each instruction and operand: whether it is the last read of that slot's value.
std::vector<std::array<bool, 3>> lastReads(const std::vector<detail::Instr>& code, std::uint32_t slots) {
  std::vector<std::array<bool, 3>> last(code.size(), {false, false, false});
  std::vector<char> live(slots, 0);
  for (std::size_t k = code.size(); k-- > 0;) {
    const detail::Instr& ins = code[k];
    const bool defines = ins.kind == InstrKind::LoadInput || ins.kind == InstrKind::LoadTransfer ||
                         ins.kind == InstrKind::Compute || ins.kind == InstrKind::SinCos;
    if (defines) live[ins.dst] = 0;
    if (ins.kind == InstrKind::SinCos) live[ins.dst2] = 0;
    for (int a = 0; a < 3; ++a) {
      const Operand& o = ins.args[a];
      if (o.kind != Operand::Kind::Slot) continue;
      const bool reads = ins.kind == InstrKind::Compute ? a < symbolic::arity(ins.op) : a == 0;
      if (!reads || ins.kind == InstrKind::LoadInput || ins.kind == InstrKind::LoadTransfer) continue;
      if (!live[o.slot]) last[k][a] = true;
      live[o.slot] = 1;
    }
  }
  return last;
}

// Slots: [constants | 3 scratch | the lowered function's locals]. Negated operands fold
// into add/sub (a + -b -> a - b) or, rarely, go through a scratch slot. A product read
// only by the add or subtract right after it fuses with it (two roundings kept: this is
// not an FMA), saving one dispatch.
class Assembler {
 public:
  explicit Assembler(std::vector<Interpreter::Instruction>& code, std::vector<double>& constants,
                     std::uint32_t locals_base)
      : code_(code), constants_(constants), base_(locals_base) {}

  static constexpr std::uint32_t kScratch = 3;

  void assemble(const detail::Chunk& chunk) {
    const auto last = lastReads(chunk.code, chunk.slots);
    for (std::size_t k = 0; k < chunk.code.size(); ++k) {
      if (k + 1 < chunk.code.size() && fuse(chunk.code[k], chunk.code[k + 1], last[k + 1])) {
        ++k;
        continue;
      }
      lowered(chunk.code[k]);
    }
  }

 private:
  static bool plainOperand(const Operand& o) { return o.kind != Operand::Kind::Slot || !o.negated; }

  // mul then add/sub of its product: one MulAdd, MulSub or SubMul.
  bool fuse(const detail::Instr& mul, const detail::Instr& next, const std::array<bool, 3>& next_last) {
    if (mul.kind != InstrKind::Compute || mul.op != Op::Mul || next.kind != InstrKind::Compute) return false;
    if (next.op != Op::Add && next.op != Op::Sub) return false;
    if (!plainOperand(mul.args[0]) || !plainOperand(mul.args[1])) return false;
    auto isProduct = [&](int a) {
      const Operand& o = next.args[a];
      return o.kind == Operand::Kind::Slot && o.slot == mul.dst && !o.negated && next_last[a];
    };
    const bool p0 = isProduct(0), p1 = isProduct(1);
    if (p0 == p1) return false;  // neither, or the product twice
    const Operand& other = next.args[p0 ? 1 : 0];
    if (other.kind == Operand::Kind::Slot && other.slot == mul.dst) return false;
    const bool negated = other.kind == Operand::Kind::Slot && other.negated;
    Code code;
    if (next.op == Op::Add) code = negated ? Code::MulSub : Code::MulAdd;  // p + c, p + -c
    else if (p0) code = negated ? Code::MulAdd : Code::MulSub;            // p - c, p - -c
    else if (!negated) code = Code::SubMul;                               // c - p
    else return false;                                                    // -c - p: rare
    emit(code, local(next.dst), slotOf(mul.args[0]), slotOf(mul.args[1]), slotOf(other));
    return true;
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
  code.push_back({Code::End, 0, 0, 0, 0});
  code_ = std::move(code);
  constants_ = std::move(constants);
  work_size_ = constants_.size() + Assembler::kScratch + chunk.slots;
}

void Interpreter::evaluate(const double* const* in, double* const* out, double* work) const { run(0, in, out, work); }

void Interpreter::evaluateBatch(std::uint64_t n, const double* const* in, double* const* out, double* work) const {
  for (std::uint64_t k = 0; k < n; ++k) run(k, in, out, work);
}

// Each operation's effect on the slots v, given the instruction i. One place, used by
// the dispatch loop below.
#define ROBODIFF_INTERPRETER_OPS(OP)                                        \
  OP(Load, v[i->dst] = in[i->a][knot * in_size[i->a] + i->b])               \
  OP(Store, out[i->a][knot * out_size[i->a] + i->b] = v[i->c])              \
  OP(StoreNeg, out[i->a][knot * out_size[i->a] + i->b] = -v[i->c])          \
  OP(Zero, std::memset(out[i->a] + knot * out_size[i->a], 0, out_size[i->a] * sizeof(double))) \
  OP(Neg, v[i->dst] = -v[i->a])                                             \
  OP(Sin, v[i->dst] = std::sin(v[i->a]))                                    \
  OP(Cos, v[i->dst] = std::cos(v[i->a]))                                    \
  OP(SinCos, ::sincos(v[i->a], &v[i->dst], &v[i->b]))                       \
  OP(Tan, v[i->dst] = std::tan(v[i->a]))                                    \
  OP(Asin, v[i->dst] = std::asin(v[i->a]))                                  \
  OP(Acos, v[i->dst] = std::acos(v[i->a]))                                  \
  OP(Atan, v[i->dst] = std::atan(v[i->a]))                                  \
  OP(Exp, v[i->dst] = std::exp(v[i->a]))                                    \
  OP(Log, v[i->dst] = std::log(v[i->a]))                                    \
  OP(Sqrt, v[i->dst] = std::sqrt(v[i->a]))                                  \
  OP(Tanh, v[i->dst] = std::tanh(v[i->a]))                                  \
  OP(Abs, v[i->dst] = std::fabs(v[i->a]))                                   \
  OP(Add, v[i->dst] = v[i->a] + v[i->b])                                    \
  OP(Sub, v[i->dst] = v[i->a] - v[i->b])                                    \
  OP(Mul, v[i->dst] = v[i->a] * v[i->b])                                    \
  OP(Div, v[i->dst] = v[i->a] / v[i->b])                                    \
  OP(Atan2, v[i->dst] = std::atan2(v[i->a], v[i->b]))                       \
  OP(Pow, v[i->dst] = std::pow(v[i->a], v[i->b]))                           \
  OP(Min, v[i->dst] = std::fmin(v[i->a], v[i->b]))                          \
  OP(Max, v[i->dst] = std::fmax(v[i->a], v[i->b]))                          \
  OP(Select, v[i->dst] = v[i->a] > 0 ? v[i->b] : v[i->c])                 \
  OP(MulAdd, v[i->dst] = v[i->a] * v[i->b] + v[i->c])                       \
  OP(MulSub, v[i->dst] = v[i->a] * v[i->b] - v[i->c])                       \
  OP(SubMul, v[i->dst] = v[i->c] - v[i->a] * v[i->b])

void Interpreter::run(std::uint64_t knot, const double* const* in, double* const* out, double* v) const {
  if (!constants_.empty()) std::memcpy(v, constants_.data(), constants_.size() * sizeof(double));
  const std::uint32_t* in_size = input_sizes_.data();
  const std::uint32_t* out_size = output_sizes_.data();
  const Instruction* i = code_.data();
  // Direct threading (GNU computed goto): one indirect jump per instruction, each
  // predicted on its own, no bounds check. code_ ends with an End instruction.
#define ROBODIFF_LABEL(name, body) &&op_##name,
  static const void* const labels[] = {ROBODIFF_INTERPRETER_OPS(ROBODIFF_LABEL) && op_End};
#undef ROBODIFF_LABEL
  goto* labels[static_cast<int>(i->code)];
#define ROBODIFF_BODY(name, body) \
  op_##name : body;               \
  ++i;                            \
  goto* labels[static_cast<int>(i->code)];
  ROBODIFF_INTERPRETER_OPS(ROBODIFF_BODY)
#undef ROBODIFF_BODY
op_End:
  return;
}

}  // namespace robodiff::codegen
