// The assembly back end's register allocation and instruction printing: one function's
// program (asm_program.hpp) as x86-64 AT&T assembly, System V calling convention,
// eval(in, out, work).
//
// The code is straight-line, so registers are allocated in one pass in program order:
// a value needs a register from its definition; when none is free, the value whose next
// use is farthest gives its register up (Belady's rule; one read back from memory at
// worst each time), stored once to a stack slot if it has no home (an input or a
// constant is read from where it is). The operand an instruction can take from memory
// is read from there when its value is not in a register.
//
// A sin-cos region first frees as many registers as it needs, so that inside it nothing
// is evicted: the cold path (libm's sincos, out of line after the function's return)
// then leaves the registers as the kernel does.
#pragma once

#include <cstdint>
#include <string>

#include "asm_constants.hpp"
#include "asm_program.hpp"

namespace robodiff::codegen::detail {

// What the host's instruction set gives the assembly: 16 xmm registers with AVX2 and
// FMA, 32 with AVX-512 (F and VL: the EVEX forms of the bitwise operations).
struct AsmTarget {
  int xmm_registers = 16;
};

// The function `symbol` (local to the library) computing `program`. Throws
// std::logic_error when the program needs more general-purpose registers for its blocks'
// pointers than the back end has (the caller checks asmBlockRegistersSuffice first).
std::string printAsmFunction(const AsmProgram& program, const std::string& symbol, const AsmTarget& target,
                             AsmConstants& constants);

// Whether the program's input and output blocks fit the general-purpose registers.
bool asmBlockRegistersSuffice(const AsmProgram& program);

}  // namespace robodiff::codegen::detail
