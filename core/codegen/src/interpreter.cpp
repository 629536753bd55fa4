#include "robodiff/codegen/interpreter.hpp"

#include <cmath>
#include <cstring>
#include <algorithm>
#include <array>
#include <map>

#include "interpreter_schedule.hpp"
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
      case InstrKind::PackPair:
      case InstrKind::ComputePair:
      case InstrKind::LoadTransferPair:
      case InstrKind::StoreTransferPair:
      case InstrKind::SinCosPair:
      case InstrKind::SinCosQuad:
        throw std::logic_error("interpreter: lane pairs");
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


// Assembles the chunk with the constants in the first slots. Their number is known only
// afterwards, so the locals are assembled against a provisional base and shifted.
void assembleConstantsFirst(const detail::Chunk& chunk, std::vector<Interpreter::Instruction>& code,
                            std::vector<double>& constants) {
  constexpr std::uint32_t kProvisional = 1u << 30;
  Assembler assembler(code, constants, kProvisional + Assembler::kScratch);
  assembler.assemble(chunk);
  const std::uint32_t shift = static_cast<std::uint32_t>(constants.size());
  auto fix = [&](std::uint32_t& s) {
    if (s >= kProvisional) s = s - kProvisional + shift;
  };
  for (Interpreter::Instruction& ins : code) {
    switch (ins.code) {
      case Code::Load: fix(ins.dst); break;
      case Code::Store:
      case Code::StoreNeg: fix(ins.c); break;
      case Code::Zero: break;
      case Code::SinCos: fix(ins.dst); fix(ins.a); fix(ins.b); break;
      default: fix(ins.dst); fix(ins.a); fix(ins.b); fix(ins.c); break;
    }
  }
}

}  // namespace

Interpreter::Interpreter(const symbolic::Graph& graph, FunctionDefinition function) : function_(std::move(function)) {
  function_.validate(graph);
  for (const auto& b : function_.inputs) input_sizes_.push_back(b.size);
  for (const auto& b : function_.outputs) output_sizes_.push_back(b.size());
  detail::LoweringOptions options;
  options.ready_first_sums = detail::readyFirstSums(graph, function_);
  const detail::LoweredFunction lowered = detail::lower(graph, function_, options);
  const detail::Chunk& chunk = lowered.chunks.at(0);
  std::vector<Instruction> code;
  std::vector<double> constants;
  assembleConstantsFirst(chunk, code, constants);
  const std::uint32_t nconst = static_cast<std::uint32_t>(constants.size());
  detail::ScheduledStream scheduled =
      detail::scheduleInstructions(code, nconst, nconst + Assembler::kScratch + chunk.slots);
  executed_ = scheduled.executed;
  groups_ = scheduled.groups;
  work_size_ = scheduled.work_size;
  stream_ = std::move(scheduled.stream);
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
