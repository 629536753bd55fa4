#include "asm_entry_kernels.hpp"

#include <algorithm>
#include <bit>
#include <map>
#include <set>
#include <unordered_map>
#include <sstream>

#include "robodiff/codegen/sincos_kernel.h"

namespace robodiff::codegen::detail {
namespace {

// %ymm0 = four arguments -> %ymm1 = their sines, %ymm2 their cosines (ymm3-15 clobbered).
// RD_SC_VECTOR's operations, contracted as a C compiler contracts them.
std::string vectorKernel(AsmConstants& k) {
  auto c = [&](double x) { return k.vector(std::bit_cast<std::uint64_t>(x)) + "(%rip)"; };
  auto q = [&](std::uint64_t bits) { return k.vector(bits) + "(%rip)"; };
  std::ostringstream s;
  s << "\tvmovapd\t" << c(RD_SC_ROUNDER) << ", %ymm3\n"  // t = x 2/pi + rounder
    << "\tvfmadd231pd\t" << c(RD_SC_TWO_OVER_PI) << ", %ymm0, %ymm3\n"
    << "\tvsubpd\t" << c(RD_SC_ROUNDER) << ", %ymm3, %ymm4\n"  // k
    << "\tvmovapd\t%ymm0, %ymm5\n\tvfnmadd231pd\t" << c(RD_SC_PIO2_1) << ", %ymm4, %ymm5\n"  // r1
    << "\tvmovapd\t%ymm5, %ymm6\n\tvfnmadd231pd\t" << c(RD_SC_PIO2_2) << ", %ymm4, %ymm6\n"  // r2
    << "\tvmulpd\t" << c(-2.0 * RD_SC_PIO2_3) << ", %ymm4, %ymm7\n\tvmulpd\t%ymm5, %ymm7, %ymm7\n"  // w
    << "\tvfmadd231pd\t%ymm6, %ymm6, %ymm7\n"  // z = r2^2 + w
    << "\tvfnmadd231pd\t" << c(RD_SC_PIO2_3) << ", %ymm4, %ymm6\n"  // r
    << "\tvmulpd\t%ymm7, %ymm7, %ymm8\n\tvmulpd\t%ymm8, %ymm8, %ymm9\n";  // z2, z4
  auto pair = [&](double c0, double c1, const char* reg) {
    s << "\tvmovapd\t" << c(c0) << ", " << reg << "\n\tvfmadd231pd\t" << c(c1) << ", %ymm7, " << reg << "\n";
  };
  pair(-1.0 / 6.0, 1.0 / 120.0, "%ymm10");
  pair(-1.0 / 5040.0, 1.0 / 362880.0, "%ymm11");
  s << "\tvfmadd231pd\t%ymm11, %ymm8, %ymm10\n";
  pair(-1.0 / 39916800.0, 1.0 / 6227020800.0, "%ymm11");
  pair(-1.0 / 1307674368000.0, 1.0 / 355687428096000.0, "%ymm12");
  s << "\tvfmadd231pd\t%ymm12, %ymm8, %ymm11\n\tvfmadd231pd\t%ymm11, %ymm9, %ymm10\n";  // st in ymm10
  pair(1.0 / 24.0, -1.0 / 720.0, "%ymm11");
  pair(1.0 / 40320.0, -1.0 / 3628800.0, "%ymm12");
  s << "\tvfmadd231pd\t%ymm12, %ymm8, %ymm11\n";
  pair(1.0 / 479001600.0, -1.0 / 87178291200.0, "%ymm12");
  s << "\tvfmadd231pd\t" << c(1.0 / 20922789888000.0) << ", %ymm8, %ymm12\n"
    << "\tvfmadd231pd\t%ymm12, %ymm9, %ymm11\n"  // ct in ymm11
    << "\tvpaddq\t" << q(1) << ", %ymm3, %ymm12\n\tvpand\t" << q(2) << ", %ymm12, %ymm12\n"
    << "\tvpsllq\t$62, %ymm12, %ymm12\n"  // sin r's sign
    << "\tvpand\t" << q(2) << ", %ymm3, %ymm13\n\tvpsllq\t$62, %ymm13, %ymm13\n"  // cos r's sign
    << "\tvpxor\t%ymm12, %ymm6, %ymm6\n"  // rs
    << "\tvmulpd\t%ymm7, %ymm6, %ymm14\n\tvfmadd213pd\t%ymm6, %ymm10, %ymm14\n"  // sp
    << "\tvmovapd\t" << c(1.0) << ", %ymm15\n\tvfnmadd231pd\t" << c(0.5) << ", %ymm7, %ymm15\n"
    << "\tvpxor\t%ymm13, %ymm15, %ymm15\n\tvpxor\t%ymm13, %ymm8, %ymm8\n"
    << "\tvfmadd231pd\t%ymm11, %ymm8, %ymm15\n"  // cp
    << "\tvpand\t" << q(1) << ", %ymm3, %ymm3\n\tvpxor\t%ymm2, %ymm2, %ymm2\n\tvpsubq\t%ymm3, %ymm2, %ymm3\n"  // swap
    << "\tvpxor\t%ymm15, %ymm14, %ymm4\n\tvpand\t%ymm3, %ymm4, %ymm4\n"
    << "\tvpxor\t%ymm4, %ymm14, %ymm1\n\tvpxor\t%ymm4, %ymm15, %ymm2\n";
  return s.str();
}

// The group's arguments into %ymm0 (missing lanes 0): one load where they are four
// neighbours of one block.
std::string loadArguments(const EntryKernelInput* lane, std::size_t n,
                          const std::function<std::string(std::uint32_t, std::uint32_t)>& input) {
  bool neighbours = n == 4;
  for (std::size_t l = 1; l < n; ++l)
    neighbours = neighbours && lane[l].block == lane[0].block && lane[l].index == lane[0].index + l;
  if (neighbours) return "\tvmovupd\t" + input(lane[0].block, lane[0].index) + ", %ymm0\n";
  std::ostringstream s;
  for (std::size_t half = 0; half * 2 < n; ++half) {
    const std::string reg = half == 0 ? "%xmm0" : "%xmm1";
    s << "\tvmovsd\t" << input(lane[2 * half].block, lane[2 * half].index) << ", " << reg << "\n";
    if (2 * half + 1 < n)
      s << "\tvmovhpd\t" << input(lane[2 * half + 1].block, lane[2 * half + 1].index) << ", " << reg << ", " << reg << "\n";
  }
  if (n > 2) s << "\tvinsertf128\t$1, %xmm1, %ymm0, %ymm0\n";
  return s.str();
}

using symbolic::Op;

bool isKernel(const Instr& ins) {
  return ins.kind == InstrKind::SinCos || (ins.kind == InstrKind::Compute && (ins.op == Op::Sin || ins.op == Op::Cos));
}

using Argument = std::pair<std::uint32_t, std::uint32_t>;  // (block, index)

// The lanes in the inputs' order (a robot's joints root first), twins side by side from
// an even lane: the pairs read most often chosen first, a lone argument moved ahead where
// a pair would start at an odd lane. Measured against the inputs' order without twins
// side by side: the free-flying Talos's CRBA 412 -> 348 ns, its RNEA value 329 -> 322;
// against the order of the body's first reads: the fixed Talos's CRBA 266 -> 250.
std::vector<EntryKernelInput> laneOrder(std::vector<Argument> arguments,
                                        const std::map<std::pair<Argument, Argument>, int>& twins) {
  std::vector<std::pair<int, std::pair<Argument, Argument>>> ranked;
  for (const auto& [pair, reads] : twins) ranked.emplace_back(-reads, pair);
  std::sort(ranked.begin(), ranked.end());
  std::set<Argument> placed;
  std::vector<std::pair<Argument, std::vector<Argument>>> units;  // (the first argument, its lanes)
  for (const auto& [reads, pair] : ranked) {
    if (placed.count(pair.first) || placed.count(pair.second)) continue;
    placed.insert(pair.first);
    placed.insert(pair.second);
    units.push_back({std::min(pair.first, pair.second), {pair.first, pair.second}});
  }
  for (const Argument& a : arguments)
    if (placed.insert(a).second) units.push_back({a, {a}});
  std::sort(units.begin(), units.end());
  std::vector<EntryKernelInput> lanes;
  std::vector<bool> done(units.size(), false);
  for (std::size_t u = 0; u < units.size(); ++u) {
    if (done[u]) continue;
    if (units[u].second.size() == 2 && lanes.size() % 2 == 1)  // the next lone argument first
      for (std::size_t v = u + 1; v < units.size(); ++v)
        if (!done[v] && units[v].second.size() == 1) {
          lanes.push_back({units[v].first.first, units[v].first.second});
          done[v] = true;
          break;
        }
    for (const Argument& a : units[u].second) lanes.push_back({a.first, a.second});
    done[u] = true;
  }
  return lanes;
}

}  // namespace

std::optional<std::vector<EntryKernelInput>> entryKernelLanes(const Chunk& chunk) {
  std::unordered_map<std::uint32_t, Argument> loaded;  // slot -> the input it holds, as last defined
  std::unordered_map<std::uint32_t, std::pair<Argument, bool>> result;  // slot -> (argument, cosine) of a kernel
  std::vector<Argument> arguments;
  std::map<std::pair<Argument, Argument>, int> twins;  // (lane 0's, lane 1's) -> packs reading them
  for (const Instr& ins : chunk.code) {
    if (isKernel(ins)) {
      const Operand& x = ins.args[0];
      auto it = x.kind == Operand::Kind::Slot && !x.negated ? loaded.find(x.slot) : loaded.end();
      if (it == loaded.end()) return std::nullopt;
      arguments.push_back(it->second);
    }
    if (ins.kind == InstrKind::PackPair) {
      auto a = result.find(ins.args[0].slot), b = result.find(ins.args[1].slot);
      const bool scalars = ins.args[0].kind == Operand::Kind::Slot && ins.args[1].kind == Operand::Kind::Slot;
      if (scalars && a != result.end() && b != result.end() && a->second.second == b->second.second &&
          a->second.first != b->second.first)
        ++twins[{a->second.first, b->second.first}];
    }
    auto redefined = [&](std::uint32_t slot) { loaded.erase(slot), result.erase(slot); };
    if (ins.kind == InstrKind::LoadInput || ins.kind == InstrKind::Compute || ins.kind == InstrKind::SinCos)
      redefined(ins.dst);
    if (ins.kind == InstrKind::SinCos) redefined(ins.dst2);
    if (ins.kind == InstrKind::LoadInput) loaded[ins.dst] = {ins.block, ins.index};
    if (isKernel(ins)) {
      const Argument x = arguments.back();
      if (ins.kind == InstrKind::SinCos) {
        result[ins.dst] = {x, false};
        result[ins.dst2] = {x, true};
      } else {
        result[ins.dst] = {x, ins.op == Op::Cos};
      }
    }
  }
  return laneOrder(std::move(arguments), twins);
}

EntryKernelCode printEntryKernels(const std::string& label, const std::vector<EntryKernelInput>& lanes,
                                  const std::function<std::string(std::uint32_t, std::uint32_t)>& input,
                                  const std::vector<std::string>& block_registers, const EntryKernelFrame& frame,
                                  AsmConstants& constants) {
  EntryKernelCode code;
  if (lanes.empty()) return code;
  std::ostringstream hot, cold;
  const std::string kernel = vectorKernel(constants);
  for (std::size_t g = 0; g * 4 < lanes.size(); ++g) {
    const std::size_t n = std::min<std::size_t>(4, lanes.size() - 4 * g);
    const int sines = frame.results + 64 * static_cast<int>(g);
    const std::string id = label + std::to_string(g);
    hot << loadArguments(&lanes[4 * g], n, input) << "\tvandpd\t" << constants.vector(0x7fffffffffffffffull)
        << "(%rip), %ymm0, %ymm1\n\tvcmppd\t$22, " << constants.vector(std::bit_cast<std::uint64_t>(RD_SC_LIMIT))
        << "(%rip), %ymm1, %ymm1\n\tvtestpd\t%ymm1, %ymm1\n\tjnz\t.L_kcold" << id << "\n"
        << kernel << "\tvmovupd\t%ymm1, " << sines << "(%rsp)\n\tvmovupd\t%ymm2, " << sines + 32 << "(%rsp)\n"
        << ".L_kjoin" << id << ":\n";
    // Cold: every lane through libm, the blocks' registers saved around the calls.
    cold << ".L_kcold" << id << ":\n";
    auto restore = [&] {
      for (std::size_t r = 0; r < block_registers.size(); ++r)
        cold << "\tmov\t" << frame.gpr_save + 8 * r << "(%rsp), " << block_registers[r] << "\n";
    };
    for (std::size_t r = 0; r < block_registers.size(); ++r)
      cold << "\tmov\t" << block_registers[r] << ", " << frame.gpr_save + 8 * r << "(%rsp)\n";
    cold << "\tvzeroupper\n";
    for (std::size_t l = 0; l < n; ++l) {
      if (l > 0) restore();
      cold << "\tvmovsd\t" << input(lanes[4 * g + l].block, lanes[4 * g + l].index) << ", %xmm0\n"
           << "\tlea\t" << sines + 8 * l << "(%rsp), %rdi\n\tlea\t" << sines + 32 + 8 * l << "(%rsp), %rsi\n"
           << "\tcall\tsincos@PLT\n";
    }
    restore();
    cold << "\tvmovupd\t" << sines << "(%rsp), %ymm1\n\tvmovupd\t" << sines + 32 << "(%rsp), %ymm2\n"  // as the hot path leaves them
         << "\tjmp\t.L_kjoin" << id << "\n";
  }
  code.hot = hot.str();
  code.cold = cold.str();
  return code;
}

}  // namespace robodiff::codegen::detail
