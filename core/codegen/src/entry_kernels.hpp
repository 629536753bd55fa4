// The sin-cos kernels of a small single-knot function computed together at its entry,
// where every kernel argument is an input (or a constant) and every operation of the
// body waits on a kernel's result: the arguments' range checked once, then the kernels
// without checks of their own or, with one argument beyond their range, every lane
// through the checked scalar kernel in a cold helper (libm's sincos for that argument).
// The kernels' sites in the body take the results. One body to compile, where the
// entry range check otherwise compiles a cold exact copy beside it
// (docs/code-generation.md, "Kernels at entry"). Internal to the C emitter.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lowering.hpp"

namespace robodiff::codegen::detail {

// One lane of a kernel's argument: an input element, maybe negated, or a constant.
struct KernelLane {
  bool constant = false;
  double value = 0.0;                  // constant
  std::uint32_t block = 0, index = 0;  // input element
  bool negated = false;                // input element
};

// A kernel of the chunk: its instruction and its argument's lanes. A pair or scalar
// kernel is one unit of the entry block, a quad two (its pairs); a scalar kernel's unit
// has one lane.
struct EntryKernel {
  std::size_t at = 0;  // the instruction's position in the chunk
  std::vector<std::vector<KernelLane>> units;
};

// The kernels of `chunk` in order, each lane traced back through the loads and packs
// that built its argument; nullopt when a lane is anything else, or when an operation
// does not wait on any kernel (its work could overlap the kernels' if they stayed in
// the body: a free-flyer's base rotation).
std::optional<std::vector<EntryKernel>> entryKernels(const Chunk& chunk);

// The entry block's C, after the body's input pointers (i0, i1, ...): `head` checks the
// arguments' range and loads them, `kernels` computes the kernels; the body's zero stores
// go between the two, so that they need not wait for the kernels (measured on the fixed
// Talos's frame Jacobian). Unit u's argument, sine and cosine are the locals
// entryUnitName(u, 'x' / 's' / 'c'), pairs (doubles for a scalar kernel). `angles`:
// (block, index) of every input a kernel takes.
struct EntryBlock {
  std::string head, kernels;
};
EntryBlock entryKernelBlock(const std::vector<EntryKernel>& kernels,
                            const std::vector<std::pair<std::uint32_t, std::uint32_t>>& angles);

// "rd_x3", "rd_s3", "rd_c3": unit u's locals.
std::string entryUnitName(std::uint32_t unit, char what);

}  // namespace robodiff::codegen::detail
