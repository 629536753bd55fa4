// The assembly back end's sin-cos kernels at a function's entry: four input arguments at
// a time in 256-bit vectors (AVX2), sincos_kernel.h's RD_SC_VECTOR operation by
// operation, results stored to the frame (asm_program.hpp, EntryKernelInput). A group
// with any argument beyond 2^19, or not a number, takes every lane through libm's
// sincos instead, out of line.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "asm_program.hpp"
#include "asm_registers.hpp"

namespace robodiff::codegen::detail {

struct EntryKernelFrame {
  int results = 0;   // byte offset of the results (64 bytes a group of four lanes)
  int gpr_save = 0;  // where the cold paths save the blocks' registers
};

// The kernels' lanes, where every sin-cos argument of the function is an input read as
// it is; nullopt otherwise. Twin arguments (whose sines, or cosines, a lane pair reads
// together) take lanes 2k and 2k + 1, so that their results are one 16-byte pair in the
// frame; the others follow in the inputs' order.
std::optional<std::vector<EntryKernelInput>> entryKernelLanes(const Chunk& chunk);

inline int entryKernelBytes(std::size_t lanes) { return static_cast<int>(64 * ((lanes + 3) / 4)); }

// The kernels' code (hot, in the prologue; the last group's results left in %ymm1 and
// %ymm2, no vzeroupper yet) and their cold paths (after the return).
// `input(block, index)` is an input's memory operand; `block_registers` the registers
// holding the blocks' pointers, saved around libm's calls.
struct EntryKernelCode {
  std::string hot, cold;
};
// `label` makes the code's labels the function's own.
EntryKernelCode printEntryKernels(const std::string& label, const std::vector<EntryKernelInput>& lanes,
                                  const std::function<std::string(std::uint32_t, std::uint32_t)>& input,
                                  const std::vector<std::string>& block_registers, const EntryKernelFrame& frame,
                                  AsmConstants& constants);

}  // namespace robodiff::codegen::detail
