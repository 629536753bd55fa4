// The assembly back end's program: a lowered single-knot function (lowering.hpp) as
// machine-level operations on immutable values, ready for register allocation
// (asm_registers.hpp).
//
// What it decides:
//  - a product read once, by a sum, is fused into that sum (one multiply-add, as a C
//    compiler contracts it);
//  - negated operands become the instructions' signs (a - b, -(a*b) + c), or one xor
//    with the sign bit where no form takes the sign;
//  - constants and inputs are values with a home in memory: they are never spilled and
//    may be read straight from memory by the operand that takes memory;
//  - where stores bound the function, four output elements are stored at once
//    (output_groups.hpp, as the C does), zeros and values packed in a 256-bit register;
//  - lane pairs (lane_pairs.hpp) are values of two doubles, computed by the packed
//    forms of the operations; a pair's lane 0 is read as a scalar as it is, lane 1
//    moved out once (High); two scalars become a pair by one unpack, a duplication, one
//    16-byte constant, or two adjacent inputs read at once;
//  - sin and cos of one argument are the kernel of sincos_kernel.h: at the entry in
//    vector lanes where every argument is an input (EntryKernelInput), else operation
//    by operation in a region: checked |x| <= 2^19 first, libm's sincos out of line
//    beyond.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "lowering.hpp"

namespace robodiff::codegen::detail {

inline constexpr std::uint32_t kNoValue = 0xffffffffu;

// Where a value can be read from memory without having been spilled.
struct ValueHome {
  enum class Kind : std::uint8_t { None, Constant, Input, EntryKernel } kind = Kind::None;
  std::uint64_t bits = 0;              // Constant: the double's (or mask's) bits
  std::uint64_t bits_high = 0;         // Constant: a pair's lane 1 (0 for a scalar)
  std::uint32_t block = 0, index = 0;  // Input; EntryKernel: index = byte offset in the results
};

// The arithmetic is scalar, or lane by lane where the result is a pair (AsmProgram::pair).
enum class MCode : std::uint8_t {
  Add, Sub, Mul, Div,  // dst = a op b
  Sqrt,       // dst = sqrt(a)
  Fma,        // dst = sign_product * (a * b) + sign_addend * c
  And, Xor,   // 128-bit bitwise: dst = a & b, a ^ b
  AddQ, SubQ, // 64-bit integer lanes: dst = a + b, a - b
  ShlQ,       // dst = a << imm (64-bit lanes)
  Pack2,      // dst = [a, b] (128 bits; a zero upper half)
  Dup,        // dst = [a, a] (a pair)
  High,       // dst = a's lane 1 (a scalar of a pair)
  Low,        // dst = [a, 0] (128 bits; a zero upper half)
  Pack4,      // dst = [a's 128 bits, b's 128 bits] (256 bits)
  Store4,     // out[block][index .. index+3] = a's 256 bits (an output group, or the constant 0)
  Store,      // out[block][index] = a
  KernelBegin,  // starts a sin-cos region on x = a (the region's registers are free first)
  KernelCheck,  // a = |x|, b = x: beyond 2^19 or not a number, the cold path (libm's sincos)
  KernelEnd,    // ends it: a = sin x, b = cos x (where the cold path joins); imm: its begin
};

struct MOp {
  MCode code = MCode::Add;
  std::uint32_t dst = kNoValue, dst2 = kNoValue;
  std::uint32_t src[3] = {kNoValue, kNoValue, kNoValue};
  bool negate_product = false, negate_addend = false;  // Fma
  std::uint32_t block = 0, index = 0;  // Store*, Load of an input
  int imm = 0;                         // ShlQ: the shift; KernelEnd: its KernelBegin's index
};

// Where every sin-cos argument is an input, the kernels run at the function's entry,
// four arguments at a time in 256-bit vectors; their results wait in the stack frame
// (64 bytes a group: four sines, then four cosines), read from there like inputs.
struct EntryKernelInput {
  std::uint32_t block = 0, index = 0;
};

struct AsmProgram {
  std::vector<MOp> ops;
  std::vector<bool> wide;  // per value: an output group's 128 or 256 bits (Pack2, Low, Pack4): never spilled
  std::vector<bool> pair;  // per value: a lane pair's two doubles (spilled to 16 bytes)
  std::vector<EntryKernelInput> entry_kernels;  // the lanes in order; empty: kernels in the body
  std::vector<ValueHome> homes;  // one per value
  std::uint32_t values() const { return static_cast<std::uint32_t>(homes.size()); }
};

// The program of a one-chunk lowered function, or nullopt when it has an operation the
// back end does not print (a call into libm other than sincos, min, max, a select).
std::optional<AsmProgram> buildAsmProgram(const Chunk& chunk, const FunctionDefinition& function);

}  // namespace robodiff::codegen::detail
