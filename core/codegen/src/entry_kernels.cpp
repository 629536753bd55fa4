#include "entry_kernels.hpp"

#include <algorithm>
#include <sstream>

#include "c_entry_points.hpp"
#include "robodiff/codegen/c_emitter.hpp"

namespace robodiff::codegen::detail {
namespace {

using Lane = std::optional<KernelLane>;
using Unit = std::vector<KernelLane>;

KernelLane negate(KernelLane l) {
  if (l.constant) l.value = -l.value;
  else l.negated = !l.negated;
  return l;
}

bool isKernel(const Instr& ins) {
  return ins.kind == InstrKind::SinCos || ins.kind == InstrKind::SinCosPair || ins.kind == InstrKind::SinCosQuad;
}

// The locals an instruction writes: scalar slots and pair slots.
struct Written {
  std::vector<std::uint32_t> slots, pairs;
};

Written written(const Instr& ins) {
  switch (ins.kind) {
    case InstrKind::LoadInput:
    case InstrKind::LoadTransfer:
    case InstrKind::Compute:
      return {{ins.dst}, {}};
    case InstrKind::SinCos:
      return {{ins.dst, ins.dst2}, {}};
    case InstrKind::PackPair:
    case InstrKind::ComputePair:
    case InstrKind::LoadTransferPair:
      return {{}, {ins.dst}};
    case InstrKind::SinCosPair:
      return {{}, {ins.dst, ins.dst2}};
    case InstrKind::SinCosQuad:
      return {{}, {ins.dst, ins.dst2, ins.dst3, ins.dst4}};
    default:
      return {};  // stores write no local
  }
}

// What each local holds while the chunk runs: where it is an input element or a
// constant (a pair local: both lanes), those; and whether it waits on a kernel.
class LocalTracker {
 public:
  explicit LocalTracker(const Chunk& chunk)
      : slots_(chunk.slots), pairs_(chunk.pair_slots), slot_waits_(chunk.slots), pair_waits_(chunk.pair_slots) {}

  Lane scalar(const Operand& o) const {
    if (o.kind == Operand::Kind::Constant) return KernelLane{true, o.value};
    if (o.kind == Operand::Kind::Input) return KernelLane{false, 0.0, o.block, o.index, o.negated};
    if (o.kind != Operand::Kind::Slot || !slots_.at(o.slot)) return std::nullopt;
    return o.negated ? negate(*slots_[o.slot]) : *slots_[o.slot];
  }

  std::optional<Unit> pair(const Operand& o) const {
    if (o.kind != Operand::Kind::Pair || !pairs_.at(o.slot)) return std::nullopt;
    Unit lanes = *pairs_[o.slot];
    if (o.negated)
      for (KernelLane& l : lanes) l = negate(l);
    return lanes;
  }

  // Whether `ins` reads a local that waits on a kernel.
  bool waits(const Instr& ins) const {
    return std::any_of(std::begin(ins.args), std::end(ins.args), [&](const Operand& o) {
      if (o.kind == Operand::Kind::Slot) return bool(slot_waits_.at(o.slot));
      if (o.kind == Operand::Kind::Pair || o.kind == Operand::Kind::Lane) return bool(pair_waits_.at(o.slot));
      return false;
    });
  }

  void write(const Instr& ins) {
    std::optional<Unit> packed;
    if (ins.kind == InstrKind::PackPair) {
      const Lane a = scalar(ins.args[0]), b = scalar(ins.args[1]);
      if (a && b) packed = Unit{*a, *b};
    }
    const bool waiting = isKernel(ins) || waits(ins);
    const Written w = written(ins);
    for (std::uint32_t s : w.slots) {
      slots_.at(s).reset();
      slot_waits_.at(s) = waiting;
    }
    for (std::uint32_t p : w.pairs) {
      pairs_.at(p).reset();
      pair_waits_.at(p) = waiting;
    }
    if (ins.kind == InstrKind::LoadInput) slots_.at(ins.dst) = KernelLane{false, 0.0, ins.block, ins.index, false};
    if (packed) pairs_.at(ins.dst) = packed;
  }

 private:
  std::vector<Lane> slots_;
  std::vector<std::optional<Unit>> pairs_;
  std::vector<char> slot_waits_, pair_waits_;
};

// A kernel's units, its argument's lanes; nullopt when a lane is not an input or a constant.
std::optional<std::vector<Unit>> kernelUnits(const Instr& ins, const LocalTracker& locals) {
  if (ins.kind == InstrKind::SinCos) {
    const Lane x = locals.scalar(ins.args[0]);
    return x ? std::optional<std::vector<Unit>>({Unit{*x}}) : std::nullopt;
  }
  std::vector<Unit> units;
  for (int a = 0; a < (ins.kind == InstrKind::SinCosQuad ? 2 : 1); ++a) {
    const auto u = locals.pair(ins.args[a]);
    if (!u) return std::nullopt;
    units.push_back(*u);
  }
  return units;
}

std::string laneText(const KernelLane& l) {
  if (l.constant) return cDoubleLiteral(l.value);
  return (l.negated ? "-i" : "i") + std::to_string(l.block) + "[" + std::to_string(l.index) + "]";
}

}  // namespace

std::string entryUnitName(std::uint32_t unit, char what) { return std::string("rd_") + what + std::to_string(unit); }

std::optional<std::vector<EntryKernel>> entryKernels(const Chunk& chunk) {
  LocalTracker locals(chunk);
  std::vector<EntryKernel> kernels;
  for (std::size_t at = 0; at < chunk.code.size(); ++at) {
    const Instr& ins = chunk.code[at];
    if (isKernel(ins)) {
      auto units = kernelUnits(ins, locals);
      if (!units) return std::nullopt;
      kernels.push_back({at, std::move(*units)});
    }
    const bool work = ins.kind == InstrKind::Compute || ins.kind == InstrKind::ComputePair;
    if (work && !locals.waits(ins)) return std::nullopt;
    locals.write(ins);
  }
  if (kernels.empty()) return std::nullopt;
  return kernels;
}

EntryBlock entryKernelBlock(const std::vector<EntryKernel>& kernels,
                            const std::vector<std::pair<std::uint32_t, std::uint32_t>>& angles) {
  if (kernels.empty() || angles.empty()) return {};
  std::ostringstream s, cold, hot;
  s << "  /* Every sin-cos kernel here, its arguments' range checked once: libm beyond it\n"
    << "     (docs/code-generation.md, \"Kernels at entry\"). */\n";
  s << beyondRangeMask("rd_beyond", angles);
  std::uint32_t u = 0;
  std::string xs;
  for (const EntryKernel& k : kernels) {
    const std::uint32_t first = u;
    for (const Unit& unit : k.units) {
      const std::string x = entryUnitName(u, 'x'), sn = entryUnitName(u, 's'), cs = entryUnitName(u, 'c');
      const std::string n = std::to_string(u);
      if (unit.size() == 1) {
        s << "  const double " << x << " = " << laneText(unit[0]) << ";\n  double " << sn << ", " << cs << ";\n";
        xs += "(rd_pair){" + x + ", " + x + "}, ";
        cold << "    " << sn << " = rd_ss[" << n << "][0];\n    " << cs << " = rd_cs[" << n << "][0];\n";
      } else {
        s << "  const rd_pair " << x << " = (rd_pair){" << laneText(unit[0]) << ", " << laneText(unit[1]) << "};\n"
          << "  rd_pair " << sn << ", " << cs << ";\n";
        xs += x + ", ";
        cold << "    " << sn << " = rd_ss[" << n << "];\n    " << cs << " = rd_cs[" << n << "];\n";
      }
      ++u;
    }
    auto arg = [&](std::uint32_t v) { return entryUnitName(v, 'x'); };
    auto outs = [&](std::uint32_t v) { return "&" + entryUnitName(v, 's') + ", &" + entryUnitName(v, 'c'); };
    if (k.units.size() == 2)
      hot << "    rd_sincos_quad_in_range(" << arg(first) << ", " << arg(first + 1) << ", " << outs(first) << ", "
          << outs(first + 1) << ");\n";
    else
      hot << "    " << (k.units[0].size() == 1 ? "rd_sincos1_in_range(" : "rd_sincos_pair_in_range(") << arg(first)
          << ", " << outs(first) << ");\n";
  }
  const std::string n = std::to_string(u);
  xs.resize(xs.size() - 2);
  std::ostringstream k;
  k << "  if (__builtin_expect((rd_beyond[0] | rd_beyond[1]) != 0, 0)) {\n"
    << "    const rd_pair rd_xs[" << n << "] = {" << xs << "};\n"
    << "    rd_pair rd_ss[" << n << "], rd_cs[" << n << "];\n"
    << "    rd_sincos_lanes_cold(" << n << ", rd_xs, rd_ss, rd_cs);\n"
    << cold.str() << "  } else {\n"
    << hot.str() << "  }\n";
  return {s.str(), k.str()};
}

}  // namespace robodiff::codegen::detail
