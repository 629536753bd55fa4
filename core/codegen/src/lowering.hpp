// Lowering: from the graph and a function definition to a straight-line program over
// numbered local slots, the one form both back ends (the C emitter and the
// interpreter) print or run.
//
// What it decides, once for both back ends:
//  - sums of several terms are chains, each product added last to a running sum, so the
//    C compiler fuses it into a multiply-add (sum_chains.hpp; this reassociates);
//  - only the nodes the outputs need are computed;
//  - constants are literals and negations are operand flags (a Neg node, or a product
//    with the constant -1, never becomes an instruction: its consumer reads the operand
//    negated, so the C reads `a - b`, not `a + (-b)`);
//  - sin(x) and cos(x) of one x become one SinCos instruction;
//  - an output block with many structural zeros (a dense Jacobian) has them cleared by
//    one ZeroOutput (a memset, or stores along its runs of zeros) instead of one store
//    instruction per zero;
//  - inputs are loaded where first used, outputs are stored right after their value is
//    computed, so a value's slot is free once its last consumer has run;
//  - slots are reused by liveness (a free list), keeping the working set small;
//  - optionally (single-knot C only) isomorphic operations are computed in pairs, in the
//    two lanes of a 128-bit vector (lane_pairs.hpp);
//  - optionally the instruction list is cut into chunks of bounded size (one per
//    translation unit); a value used by a later chunk goes through the work buffer
//    ("transfer" slots, also reused once their last reader is done).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen::detail {

struct Operand {
  // Slot: a scalar local; Lane: one lane of a pair local; Pair: a pair local (the
  // operands of ComputePair only).
  enum class Kind : std::uint8_t { Slot, Constant, Input, Lane, Pair };
  Kind kind = Kind::Slot;
  bool negated = false;            // all but Constant; a Constant carries its sign
  std::uint8_t lane = 0;           // Lane
  std::uint32_t slot = 0;          // Slot, Lane, Pair
  double value = 0.0;              // Constant
  std::uint32_t block = 0, index = 0;  // Input (only in output copies: out = +-in)
};

enum class InstrKind : std::uint8_t {
  LoadInput,      // slot dst = in[block][index]
  LoadTransfer,   // slot dst = work[index]
  Compute,        // slot dst = op(args)
  SinCos,         // slot dst = sin(args[0]), slot dst2 = cos(args[0])
  StoreOutput,    // out[block][index] = args[0]
  StoreTransfer,  // work[index] = args[0]
  ZeroOutput,     // out[block] = 0 on the runs chunk.zero_runs[index] (before the block's other stores)
  PackPair,       // pair dst = {args[0], args[1]} (two scalar operands)
  ComputePair,    // pair dst = op(args), lane by lane (Pair operands)
  LoadTransferPair,   // pair dst = {work[index], work[index + 1]}
  StoreTransferPair,  // {work[index], work[index + 1]} = pair args[0]
  SinCosPair,         // pair dst = sin(pair args[0]), pair dst2 = cos(pair args[0])
  SinCosQuad,         // SinCosPair's, and pairs dst3, dst4 of pair args[1], in one call
};

struct Instr {
  InstrKind kind = InstrKind::Compute;
  symbolic::Op op = symbolic::Op::Constant;  // Compute
  std::uint32_t dst = 0, dst2 = 0, dst3 = 0, dst4 = 0;
  Operand args[3];
  std::uint32_t block = 0, index = 0;
};

// Entries [start, start + length) of an output block.
struct ZeroRun {
  std::uint32_t start = 0, length = 0;
};

// The stores that write a block's zero runs (`size` elements), in order: each group of
// four from element 4k holding a zero once, group(4k), and each zero of a tail shorter
// than four alone, single(k). What the single-knot printer emits and output groups count.
template <class Group, class Single>
void forEachZeroStore(const std::vector<ZeroRun>& runs, std::uint32_t size, Group group, Single single) {
  std::uint32_t cleared_to = 0;  // elements below this are written
  for (const ZeroRun& r : runs)
    for (std::uint32_t k = std::max(r.start, cleared_to); k < r.start + r.length; k = std::max(k + 1, cleared_to)) {
      if (k / 4 * 4 + 4 <= size) {
        group(k / 4 * 4);
        cleared_to = k / 4 * 4 + 4;
      } else {
        single(k);
      }
    }
}

struct Chunk {
  std::vector<Instr> code;
  std::vector<std::vector<ZeroRun>> zero_runs;  // per ZeroOutput (its index), ascending
  std::uint32_t slots = 0;       // local slots used (highest slot + 1)
  std::uint32_t pair_slots = 0;  // pair locals used
  std::uint32_t operations = 0;  // Compute + SinCos instructions
};

struct LoweredFunction {
  std::vector<Chunk> chunks;        // at least one
  std::uint32_t transfer_slots = 0; // doubles of work buffer passing values between chunks
  std::uint32_t needed_nodes = 0;   // graph nodes the outputs reach (constants and inputs included)
  std::uint32_t operations = 0;
  std::uint32_t sincos_pairs = 0;
  std::uint32_t lane_pairs = 0;     // ComputePair instructions
  std::uint32_t sincos_lane_pairs = 0;  // SinCosPair and SinCosQuad instructions
  // (block, index) of the inputs the sin-cos kernels take, in order, when every kernel's
  // argument is an input; empty otherwise (or without kernels).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> sincos_inputs;
};

// Lane pairs (lane_pairs.hpp): Off; Order: the pairs' order without pairs (the code
// both flavours of a C library share parts and work buffer with); Emit: the pairs too.
enum class LanePairMode : std::uint8_t { Off, Order, Emit };

// Functions of this many operations and more get no lane pairs (the output order's
// large Jacobians, where they were not measured).
inline constexpr std::uint32_t kLanePairsBelow = kOutputOrderFrom;
// Lane pairs are kept where they compute at least this share of the operations. Measured
// (docs/code-generation.md): the value functions of symmetric robots with 41-85% in pairs
// ran 1.06-2x faster; with 14-24% in pairs, up to 1.15x slower.
inline constexpr double kLanePairCoverage = 0.3;
// The same for a derivative function's pairs (seeded at twins only): Talos fixed ABA + J
// and Euler step + J, 26-27% in pairs, ran 1.08-1.19x faster with them.
inline constexpr double kTwinPairCoverage = 0.2;

struct LanePairMemo;  // lane_pairs.hpp

struct LoweringOptions {
  std::uint32_t split_threshold = 0;  // operations per chunk; 0: one chunk
  bool reuse_slots = true;            // false: every value gets a fresh slot (SSA form)
  bool chain_sums = true;             // false: sums as the graph associates them
  // From this many operations on, values are computed output by output (emission_order.hpp)
  // instead of in the trace's order; 0: never.
  std::uint32_t output_order_from = kOutputOrderFrom;
  LanePairMode lane_pairs = LanePairMode::Off;
  bool ready_first_sums = false;  // sum chains take their terms in order of readiness (sum_chains.hpp)
  LanePairMemo* lane_pair_memo = nullptr;  // shared by one function's lowerings; not owned
  // With lane pairs, sin and cos of two to four arguments in the lanes of one kernel
  // (SinCosPair, SinCosQuad); false: each its own SinCos (the assembly's kernels take
  // four input arguments at once by themselves).
  bool sincos_lanes = true;
};

// Expects a definition that passed validate(graph).
LoweredFunction lower(const symbolic::Graph& graph, const FunctionDefinition& function,
                      const LoweringOptions& options = {});

// Whether the function's sum chains take their terms in order of readiness: where its
// code has no lane pairs (a serial robot's). Reordered chains cost a twin-limbed robot's
// functions a share of their lane pairs (the free-flying Talos's RNEA + J all of them).
// The C code and the interpreter both ask, so they compute the same chains.
bool readyFirstSums(const symbolic::Graph& graph, const FunctionDefinition& function, LanePairMemo* memo = nullptr);

// readyFirstSums with the memo it fills (lane_pairs.hpp).
struct FunctionPairing;
FunctionPairing pairingOf(const symbolic::Graph& graph, const FunctionDefinition& function);

}  // namespace robodiff::codegen::detail
