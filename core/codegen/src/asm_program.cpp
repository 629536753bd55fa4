#include "asm_program.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <tuple>
#include <unordered_map>

#include "asm_entry_kernels.hpp"
#include "output_groups.hpp"
#include "robodiff/codegen/sincos_kernel.h"

namespace robodiff::codegen::detail {
namespace {

using symbolic::Op;

constexpr std::uint64_t kSignBit = 0x8000000000000000ull;
constexpr std::uint64_t kAbsMask = 0x7fffffffffffffffull;

std::uint64_t bitsOf(double x) { return std::bit_cast<std::uint64_t>(x); }

// A lowered operand as a value: the value and whether it is read negated.
struct Signed {
  std::uint32_t value = kNoValue;
  bool negated = false;
};

class Builder {
 public:
  Builder(const Chunk& chunk, const FunctionDefinition& function) : chunk_(chunk), function_(function) {}

  std::optional<AsmProgram> build() {
    if (!supported()) return std::nullopt;
    countUses();
    planEntryKernels();
    groups_ = planOutputGroups(function_, chunk_, 0xffffffffu);  // zeros are always stored, never a memset
    group_values_.assign(groups_.groups.size() * 4, kNoValue);
    for (std::size_t i = 0; i < chunk_.code.size(); ++i) emitInstr(chunk_.code[i], i);
    program_.wide.resize(program_.values(), false);
    program_.pair.resize(program_.values(), false);
    return std::move(program_);
  }

 private:
  // Everything but libm calls other than sincos, min, max and selects, transfers
  // (one part only) and sin-cos lanes (the kernels at entry take four lanes themselves).
  bool supported() const {
    for (const Instr& ins : chunk_.code) {
      switch (ins.kind) {
        case InstrKind::LoadInput: case InstrKind::SinCos: case InstrKind::StoreOutput: case InstrKind::ZeroOutput:
        case InstrKind::PackPair:
          break;
        case InstrKind::ComputePair:  // the operations lane pairs take (lane_pairs.cpp)
          if (ins.op != Op::Add && ins.op != Op::Sub && ins.op != Op::Mul && ins.op != Op::Div) return false;
          break;
        case InstrKind::Compute:
          switch (ins.op) {
            case Op::Add: case Op::Sub: case Op::Mul: case Op::Div: case Op::Neg: case Op::Sqrt: case Op::Abs:
            case Op::Sin: case Op::Cos:  // the kernel, one of its results unused
              break;
            default:
              return false;
          }
          break;
        default:
          return false;
      }
    }
    return true;
  }

  // The kernels' lanes at entry, when every sin-cos argument is an input read as it is.
  void planEntryKernels() {
    std::optional<std::vector<EntryKernelInput>> lanes = entryKernelLanes(chunk_);
    if (!lanes) return;
    program_.entry_kernels = std::move(*lanes);
    for (std::size_t lane = 0; lane < program_.entry_kernels.size(); ++lane) {
      const EntryKernelInput& x = program_.entry_kernels[lane];
      lane_of_[{x.block, x.index}] = static_cast<std::uint32_t>(lane);
    }
    kernels_at_entry_ = true;
  }

  // A local's key: scalar slots and pair slots are numbered apart.
  static constexpr std::uint64_t kPairKey = std::uint64_t{1} << 32;
  static std::uint64_t key(const Operand& o) {
    return o.kind == Operand::Kind::Slot ? o.slot : kPairKey | o.slot;
  }

  // The products read once, by a sum of their kind (scalar or pair): those are fused into it.
  void countUses() {
    std::unordered_map<std::uint64_t, std::size_t> slot_def;  // local -> defining instruction
    std::vector<int> uses(chunk_.code.size(), 0);
    auto definer = [&](const Operand& o) -> std::size_t {
      if (o.kind != Operand::Kind::Slot && o.kind != Operand::Kind::Pair && o.kind != Operand::Kind::Lane)
        return SIZE_MAX;
      auto it = slot_def.find(key(o));
      return it == slot_def.end() ? SIZE_MAX : it->second;
    };
    std::vector<std::array<std::size_t, 3>> readers(chunk_.code.size());
    for (std::size_t i = 0; i < chunk_.code.size(); ++i) {
      const Instr& ins = chunk_.code[i];
      for (int a = 0; a < 3; ++a) {
        readers[i][a] = definer(ins.args[a]);
        if (readers[i][a] != SIZE_MAX && reads(ins, a)) ++uses[readers[i][a]];
      }
      if (ins.kind == InstrKind::LoadInput || ins.kind == InstrKind::Compute) slot_def[ins.dst] = i;
      if (ins.kind == InstrKind::SinCos) slot_def[ins.dst] = slot_def[ins.dst2] = SIZE_MAX;
      if (ins.kind == InstrKind::ComputePair || ins.kind == InstrKind::PackPair) slot_def[kPairKey | ins.dst] = i;
    }
    fused_.assign(chunk_.code.size(), false);
    fused_into_.assign(chunk_.code.size(), -1);
    for (std::size_t i = 0; i < chunk_.code.size(); ++i) {
      const Instr& ins = chunk_.code[i];
      if (!isArithmetic(ins) || (ins.op != Op::Add && ins.op != Op::Sub)) continue;
      for (int a = 1; a >= 0; --a) {
        const std::size_t d = readers[i][a];
        if (d == SIZE_MAX || uses[d] != 1 || ins.args[a].kind == Operand::Kind::Lane) continue;
        const Instr& def = chunk_.code[d];
        if (def.kind != ins.kind || def.op != Op::Mul || fused_[d]) continue;
        fused_[d] = true;
        fused_into_[i] = a;
        break;
      }
    }
  }

  static bool isArithmetic(const Instr& ins) {
    return ins.kind == InstrKind::Compute || ins.kind == InstrKind::ComputePair;
  }
  static bool reads(const Instr& ins, int a) {
    switch (ins.kind) {
      case InstrKind::Compute: case InstrKind::ComputePair: return a < symbolic::arity(ins.op);
      case InstrKind::PackPair: return a < 2;
      case InstrKind::SinCos: case InstrKind::StoreOutput: return a == 0;
      default: return false;
    }
  }

  // A value: a pair while a lane pair's operation is built (packed_).
  std::uint32_t newValue(ValueHome home = {}, bool pair = false) {
    program_.homes.push_back(home);
    program_.pair.resize(program_.values(), false);
    program_.pair.back() = pair || packed_;
    return program_.values() - 1;
  }
  // One value per constant: the allocator keeps one read often in a register. While a
  // lane pair's operation is built, the constant in both lanes.
  std::uint32_t constant(std::uint64_t bits) { return packed_ ? constantPair(bits, bits) : constantPair(bits, 0, false); }
  std::uint32_t constant(double x) { return constant(bitsOf(x)); }
  std::uint32_t constantPair(std::uint64_t low, std::uint64_t high, bool pair = true) {
    auto [it, fresh] = constants_.emplace(std::make_tuple(low, high, pair), kNoValue);
    if (!fresh) return it->second;
    ValueHome h;
    h.kind = ValueHome::Kind::Constant;
    h.bits = low;
    h.bits_high = pair ? high : 0;
    return it->second = newValue(h, pair);
  }
  // A constant with its sign (both lanes' for a pair) flipped.
  std::uint32_t flipped(std::uint32_t v) {
    const ValueHome h = program_.homes[v];
    if (!program_.pair[v]) return constantPair(h.bits ^ kSignBit, 0, false);
    return constantPair(h.bits ^ kSignBit, h.bits_high ^ kSignBit);
  }

  std::uint32_t emit(MCode code, std::uint32_t a = kNoValue, std::uint32_t b = kNoValue, std::uint32_t c = kNoValue) {
    MOp op;
    op.code = code;
    op.src[0] = a;
    op.src[1] = b;
    op.src[2] = c;
    op.dst = newValue();
    program_.ops.push_back(op);
    return op.dst;
  }
  std::uint32_t fma(std::uint32_t a, std::uint32_t b, std::uint32_t c, bool negate_product = false,
                    bool negate_addend = false) {
    const std::uint32_t d = emit(MCode::Fma, a, b, c);
    program_.ops.back().negate_product = negate_product;
    program_.ops.back().negate_addend = negate_addend;
    return d;
  }
  std::uint32_t negate(std::uint32_t v) { return emit(MCode::Xor, v, constant(kSignBit)); }

  Signed operand(const Operand& o) {
    switch (o.kind) {
      case Operand::Kind::Slot: case Operand::Kind::Pair: return {local_.at(key(o)), o.negated};
      case Operand::Kind::Lane: return {lane(local_.at(key(o)), o.lane), o.negated};
      case Operand::Kind::Constant: return {constant(o.value), false};
      case Operand::Kind::Input: {
        ValueHome h;
        h.kind = ValueHome::Kind::Input;
        h.block = o.block;
        h.index = o.index;
        return {newValue(h), o.negated};
      }
    }
    throw std::logic_error("asm_program: an unknown operand");
  }

  // A pair's lane as a scalar: a constant's or an input's own value; lane 0 of a
  // computed pair the pair itself (scalar operations read the low lane), lane 1 moved
  // out once.
  std::uint32_t lane(std::uint32_t pair, std::uint8_t which) {
    const ValueHome h = program_.homes[pair];
    if (h.kind == ValueHome::Kind::Constant) return constantPair(which ? h.bits_high : h.bits, 0, false);
    if (h.kind == ValueHome::Kind::Input) {
      ValueHome x = h;
      x.index += which;
      return newValue(x);
    }
    if (which == 0) return pair;
    auto [it, fresh] = high_of_.emplace(pair, kNoValue);
    if (fresh) it->second = emit(MCode::High, pair);
    return it->second;
  }
  // The operand's value with its sign applied.
  std::uint32_t plain(const Operand& o) {
    const Signed s = operand(o);
    return s.negated ? negate(s.value) : s.value;
  }

  // The pair [x, y] of two scalar operands: two constants one 16-byte constant, two
  // adjacent inputs or twin kernels' results read at once, one value duplicated, else
  // one unpack.
  std::uint32_t pack(const Operand& x, const Operand& y) {
    const Signed a = operand(x), b = operand(y);
    const ValueHome ha = program_.homes[a.value], hb = program_.homes[b.value];
    if (ha.kind == ValueHome::Kind::Constant && hb.kind == ValueHome::Kind::Constant)
      return constantPair(ha.bits ^ (a.negated ? kSignBit : 0), hb.bits ^ (b.negated ? kSignBit : 0));
    if (ha.kind == ValueHome::Kind::Input && hb.kind == ValueHome::Kind::Input && ha.block == hb.block &&
        hb.index == ha.index + 1 && !a.negated && !b.negated)
      return newValue(ha, true);
    if (ha.kind == ValueHome::Kind::EntryKernel && hb.kind == ValueHome::Kind::EntryKernel &&
        hb.index == ha.index + 8 && ha.index % 16 == 0 && !a.negated && !b.negated)
      return newValue(ha, true);  // twin kernels' results, side by side in the frame
    const auto key = std::make_tuple(a.value, a.negated, b.value, b.negated);
    if (auto it = packs_.find(key); it != packs_.end()) return it->second;  // packed before: read again
    std::uint32_t d;
    if (a.value == b.value && a.negated == b.negated) {
      d = emit(MCode::Dup, plain(x));
    } else {
      const std::uint32_t pa = plain(x), pb = plain(y);
      d = emit(MCode::Pack2, pa, pb);
    }
    program_.pair[d] = true;
    return packs_[key] = d;
  }

  void emitInstr(const Instr& ins, std::size_t i) {
    switch (ins.kind) {
      case InstrKind::LoadInput: {
        ValueHome h;
        h.kind = ValueHome::Kind::Input;
        h.block = ins.block;
        h.index = ins.index;
        local_[ins.dst] = newValue(h);
        return;
      }
      case InstrKind::Compute: return emitCompute(ins, i);
      case InstrKind::SinCos: {
        if (kernels_at_entry_) return entryKernelResults(ins);
        const auto [s, c] = sincos(plain(ins.args[0]));
        local_[ins.dst] = s;
        local_[ins.dst2] = c;
        return;
      }
      case InstrKind::StoreOutput: {
        const std::uint32_t v = plain(ins.args[0]);
        if (groups_.group_of[i] != kNoGroup) return storeInGroup(groups_.group_of[i], ins.index, v, i);
        MOp op;
        op.code = MCode::Store;
        op.src[0] = v;
        op.block = ins.block;
        op.index = ins.index;
        program_.ops.push_back(op);
        return;
      }
      case InstrKind::ZeroOutput: return emitZeros(ins);
      case InstrKind::PackPair: local_[kPairKey | ins.dst] = pack(ins.args[0], ins.args[1]); return;
      case InstrKind::ComputePair:
        packed_ = true;  // results and constants in both lanes
        emitCompute(ins, i);
        packed_ = false;
        return;
      default: throw std::logic_error("asm_program: an instruction only C prints");
    }
  }

  // sin and cos of an input, computed at entry: values at home in the frame (a lone sin
  // or cos, ins.op, takes one of them).
  void entryKernelResults(const Instr& ins) {
    const ValueHome& x = program_.homes.at(local_.at(ins.args[0].slot));
    const std::uint32_t lane = lane_of_.at({x.block, x.index});
    ValueHome h;
    h.kind = ValueHome::Kind::EntryKernel;
    h.index = 64 * (lane / 4) + 8 * (lane % 4);
    if (ins.kind == InstrKind::Compute) {
      if (ins.op == Op::Cos) h.index += 32;
      local_[ins.dst] = newValue(h);
      return;
    }
    local_[ins.dst] = newValue(h);
    h.index += 32;
    local_[ins.dst2] = newValue(h);
  }

  // An element of an output group; at the group's last store, the group's four
  // elements (zeros as the constant 0) in one 256-bit store.
  void storeInGroup(std::uint32_t group, std::uint32_t index, std::uint32_t value, std::size_t at) {
    const OutputGroup& g = groups_.groups[group];
    group_values_[4 * group + (index - g.start)] = value;
    if (g.last != at) return;
    const std::uint32_t* e = &group_values_[4 * group];
    const std::uint32_t low = half(e[0], e[1]), high = half(e[2], e[3]);
    MOp store;
    store.code = MCode::Store4;
    store.src[0] = high == zero() ? low : wideValue(MCode::Pack4, low, high);
    store.block = g.block;
    store.index = g.start;
    program_.ops.push_back(store);
  }
  // Two elements in 128 bits, the upper half of the 256 zero.
  std::uint32_t half(std::uint32_t a, std::uint32_t b) {
    if (a == kNoValue && b == kNoValue) return zero();
    if (b == kNoValue) return wideValue(MCode::Low, a);
    return wideValue(MCode::Pack2, a == kNoValue ? zero() : a, b);
  }
  std::uint32_t wideValue(MCode code, std::uint32_t a, std::uint32_t b = kNoValue) {
    const std::uint32_t v = emit(code, a, b);
    program_.wide.resize(program_.values(), false);
    program_.wide[v] = true;
    return v;
  }
  // The constant 0, read by vmovsd: the whole register zero.
  std::uint32_t zero() { return constant(std::uint64_t{0}); }

  // A block's zero runs: each group of four from element 4k holding a zero cleared
  // whole (the block's other stores come after), a shorter tail's zeros one by one;
  // output groups hold their own zeros.
  void emitZeros(const Instr& ins) {
    auto store = [&](MCode code, std::uint32_t index) {
      MOp op;
      op.code = code;
      op.src[0] = zero();
      op.block = ins.block;
      op.index = index;
      program_.ops.push_back(op);
    };
    forEachZeroStore(
        chunk_.zero_runs[ins.index], function_.outputs[ins.block].size(),
        [&](std::uint32_t group) {
          if (!groups_.packs(ins.block, group)) store(MCode::Store4, group);
        },
        [&](std::uint32_t k) { store(MCode::Store, k); });
  }

  void emitCompute(const Instr& ins, std::size_t i) {
    const std::uint64_t dst = ins.kind == InstrKind::ComputePair ? kPairKey | ins.dst : ins.dst;
    if (fused_[i]) {  // computed by its sum
      products_[dst] = {operand(ins.args[0]), operand(ins.args[1])};
      local_[dst] = kNoValue;
      return;
    }
    switch (ins.op) {
      case Op::Add: case Op::Sub: return local_[dst] = sum(ins, i), void();
      case Op::Mul: case Op::Div: {
        Signed a = operand(ins.args[0]), b = operand(ins.args[1]);
        bool negative = a.negated != b.negated;
        for (Signed* x : {&a, &b})  // the sign into a constant factor
          if (negative && program_.homes[x->value].kind == ValueHome::Kind::Constant) {
            x->value = flipped(x->value);
            negative = false;
          }
        const std::uint32_t r = emit(ins.op == Op::Mul ? MCode::Mul : MCode::Div, a.value, b.value);
        local_[dst] = negative ? negate(r) : r;
        return;
      }
      case Op::Neg: {
        const Signed a = operand(ins.args[0]);
        local_[dst] = a.negated ? a.value : negate(a.value);
        return;
      }
      case Op::Sqrt: local_[dst] = emit(MCode::Sqrt, plain(ins.args[0])); return;
      case Op::Sin: case Op::Cos: {
        if (kernels_at_entry_) return entryKernelResults(ins);
        const auto [s, c] = sincos(plain(ins.args[0]));
        local_[dst] = ins.op == Op::Sin ? s : c;
        return;
      }
      case Op::Abs: local_[dst] = emit(MCode::And, operand(ins.args[0]).value, constant(kAbsMask)); return;
      default: throw std::logic_error("asm_program: an unsupported operation");
    }
  }

  // a + b or a - b, the operands' signs folded in; a product read only here fused.
  std::uint32_t sum(const Instr& ins, std::size_t i) {
    Signed t[2] = {operandOrProduct(ins.args[0]), operandOrProduct(ins.args[1])};
    if (ins.op == Op::Sub) t[1].negated = !t[1].negated;
    const int p = fused_into_[i];
    if (p >= 0) {
      const auto& [a, b] = products_.at(key(ins.args[p]));
      const Signed& addend = t[1 - p];
      const bool negative_product = t[p].negated != (a.negated != b.negated);
      return fma(a.value, b.value, addend.value, negative_product, addend.negated);
    }
    if (!t[0].negated && !t[1].negated) return emit(MCode::Add, t[0].value, t[1].value);
    if (!t[0].negated) return emit(MCode::Sub, t[0].value, t[1].value);
    if (!t[1].negated) return emit(MCode::Sub, t[1].value, t[0].value);
    return negate(emit(MCode::Add, t[0].value, t[1].value));
  }
  Signed operandOrProduct(const Operand& o) {
    if ((o.kind == Operand::Kind::Slot || o.kind == Operand::Kind::Pair) && local_.at(key(o)) == kNoValue)
      return {kNoValue, o.negated};
    return operand(o);
  }

  // sincos_kernel.h's kernel on x, in a region with its range check; (sin x, cos x).
  std::pair<std::uint32_t, std::uint32_t> sincos(std::uint32_t x) {
    MOp begin;
    begin.code = MCode::KernelBegin;
    begin.src[0] = x;
    const std::size_t begin_at = program_.ops.size();
    program_.ops.push_back(begin);
    MOp check;
    check.code = MCode::KernelCheck;
    check.src[0] = emit(MCode::And, x, constant(kAbsMask));
    check.src[1] = x;
    program_.ops.push_back(check);
    // The reduction: t's low bits hold the quadrant; r = x - k pi/2; z = r^2.
    const std::uint32_t t = fma(x, constant(RD_SC_TWO_OVER_PI), constant(RD_SC_ROUNDER));
    const std::uint32_t k = emit(MCode::Sub, t, constant(RD_SC_ROUNDER));
    const std::uint32_t r1 = fma(k, constant(RD_SC_PIO2_1), x, true);
    const std::uint32_t r2 = fma(k, constant(RD_SC_PIO2_2), r1, true);
    const std::uint32_t w = emit(MCode::Mul, emit(MCode::Mul, k, constant(-2.0 * RD_SC_PIO2_3)), r1);
    const std::uint32_t z = fma(r2, r2, w);
    const std::uint32_t r = fma(k, constant(RD_SC_PIO2_3), r2, true);
    // The polynomials' tails by Estrin's scheme.
    const std::uint32_t z2 = emit(MCode::Mul, z, z), z4 = emit(MCode::Mul, z2, z2);
    auto pair = [&](double c0, double c1) { return fma(z, constant(c1), constant(c0)); };
    const std::uint32_t s01 = pair(-1.0 / 6.0, 1.0 / 120.0), s23 = pair(-1.0 / 5040.0, 1.0 / 362880.0);
    const std::uint32_t s45 = pair(-1.0 / 39916800.0, 1.0 / 6227020800.0);
    const std::uint32_t s67 = pair(-1.0 / 1307674368000.0, 1.0 / 355687428096000.0);
    const std::uint32_t st = fma(z4, fma(z2, s67, s45), fma(z2, s23, s01));
    const std::uint32_t c01 = pair(1.0 / 24.0, -1.0 / 720.0), c23 = pair(1.0 / 40320.0, -1.0 / 3628800.0);
    const std::uint32_t c45 = pair(1.0 / 479001600.0, -1.0 / 87178291200.0);
    const std::uint32_t ct = fma(z4, fma(z2, constant(1.0 / 20922789888000.0), c45), fma(z2, c23, c01));
    // The quadrant's signs before the last operations, then the swap (RD_SC_VECTOR).
    const std::uint32_t two = constant(std::uint64_t{2});
    const std::uint32_t sin_r_sign = emit(MCode::And, emit(MCode::AddQ, t, constant(std::uint64_t{1})), two);
    const std::uint32_t sin_sign = shl62(sin_r_sign);
    const std::uint32_t cos_sign = shl62(emit(MCode::And, t, two));
    const std::uint32_t rs = emit(MCode::Xor, r, sin_sign);
    const std::uint32_t sp = fma(emit(MCode::Mul, rs, z), st, rs);
    const std::uint32_t half = fma(z, constant(0.5), constant(1.0), true);
    const std::uint32_t cp = fma(emit(MCode::Xor, z2, cos_sign), ct, emit(MCode::Xor, half, cos_sign));
    const std::uint32_t odd = emit(MCode::And, t, constant(std::uint64_t{1}));
    const std::uint32_t swap = emit(MCode::SubQ, zero(), odd);
    const std::uint32_t d = emit(MCode::And, emit(MCode::Xor, sp, cp), swap);
    const std::uint32_t s = emit(MCode::Xor, sp, d), c = emit(MCode::Xor, cp, d);
    MOp end;
    end.code = MCode::KernelEnd;
    end.src[0] = s;
    end.src[1] = c;
    end.imm = static_cast<int>(begin_at);
    program_.ops.push_back(end);
    return {s, c};
  }
  std::uint32_t shl62(std::uint32_t v) {
    const std::uint32_t d = emit(MCode::ShlQ, v);
    program_.ops.back().imm = 62;
    return d;
  }

  const Chunk& chunk_;
  const FunctionDefinition& function_;
  AsmProgram program_;
  std::vector<bool> fused_;
  std::vector<int> fused_into_;  // per sum: which operand is its fused product, or -1
  std::unordered_map<std::uint64_t, std::uint32_t> local_;  // local (key()) -> its value
  std::unordered_map<std::uint64_t, std::pair<Signed, Signed>> products_;  // fused product's local -> factors
  bool packed_ = false;  // a lane pair's operation is being built
  std::unordered_map<std::uint32_t, std::uint32_t> high_of_;  // pair -> its lane 1
  std::map<std::tuple<std::uint32_t, bool, std::uint32_t, bool>, std::uint32_t> packs_;  // two signed scalars -> their pair
  std::map<std::tuple<std::uint64_t, std::uint64_t, bool>, std::uint32_t> constants_;  // (bits, high, pair) -> value
  bool kernels_at_entry_ = false;  // the kernels run at entry
  OutputGroupPlan groups_;
  std::vector<std::uint32_t> group_values_;  // per group, its four elements' values (kNoValue: zero)
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> lane_of_;  // (block, index) -> lane
};

}  // namespace

std::optional<AsmProgram> buildAsmProgram(const Chunk& chunk, const FunctionDefinition& function) {
  return Builder(chunk, function).build();
}

}  // namespace robodiff::codegen::detail
