// C source generation: a graph and function definitions in, the C sources of a
// self-describing shared library out (see abi.h for the ABI it implements).
//
// The code is straight-line C99 (plus GNU vector extensions for the batched entry
// point, compiled only by compilers that have them; others get a plain loop):
// plain scalar locals (`double t4 = t1 * t2;`) reused by liveness, isomorphic
// operations two at a time in one 128-bit vector where that pays (lane pairs, GNU
// vector types), sin/cos of one argument from one inline kernel, negations folded into
// their consumers, constants printed exactly (shortest round-trip form), no fast-math
// assumptions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/symbolic/graph.hpp"

namespace robodiff::codegen {

// Changes whenever the generated code changes for the same input (part of cache keys).
inline constexpr const char* kGeneratorVersion = "robodiff-codegen 0.5.2";

// Functions of at least this many operations compute their values output by output,
// not in the trace's order (src/emission_order.hpp). Measured (docs/code-generation.md):
// four functions of the free-flying Talos of 72k-137k operations ran 7-21% faster so,
// seven functions of 1k-47k operations 4-15% slower.
inline constexpr std::uint32_t kOutputOrderFrom = 60000;

// Functions whose single-knot code issues at least this many instructions (operations
// less lane pairs) address their arrays and constants compactly (src/compact_addressing.hpp):
// their code no longer fits the instruction cache and runs at the speed it streams in.
// Below, it fits, and the base pointers only take registers (docs/code-generation.md).
// Each of those takes 7.8 bytes of machine code or so (-march=native: Panda Euler step + J,
// 64,033 bytes for 8,228; its step + cost + derivatives, 70,833 for 8,989; the
// free-flying Talos's step + cost value, 63,713 for 8,222), so this is where a 32 KiB
// instruction cache fills; compactAddressingFrom() scales it to another.
inline constexpr std::uint64_t kCompactAddressingCacheBytes = 32768;
inline constexpr double kCodeBytesPerInstruction = 7.8;
inline constexpr std::uint64_t kCompactAddressingFrom =
    static_cast<std::uint64_t>(kCompactAddressingCacheBytes / kCodeBytesPerInstruction);

// The threshold for an instruction cache of `bytes` (0: unknown, the 32 KiB one's).
std::uint64_t compactAddressingFrom(std::uint64_t instruction_cache_bytes);
// The level-1 instruction cache of the CPU this runs on, in bytes; 0 if unknown.
std::uint64_t hostInstructionCacheBytes();

struct CodegenOptions {
  // Operations per translation unit before a function is cut into parts compiled
  // separately (in parallel); values crossing parts go through the work buffer.
  // 0: never split.
  std::uint32_t split_threshold = 0;
  // Reuse a local once its value is dead (false: one local per value).
  bool reuse_temporaries = true;
  // The batched entry point evaluates this many knots at once in SIMD lanes.
  // 0: chosen by the target at compile time (8 with AVX-512, 4 with AVX, else 2);
  // 1: no SIMD variant, eval_batch loops over eval (also what compilers without GNU
  // vector extensions, such as tcc, always get); else 2, 4, 8 or 16 lanes.
  std::uint32_t batch_width = 0;
  // Operations from which values are computed output by output; 0: always the trace's order.
  std::uint32_t output_order_from = kOutputOrderFrom;
  // Single-knot code computes isomorphic operations in pairs, in the two lanes of a
  // 128-bit vector (where the compiler has GNU vector extensions).
  bool lane_pairs = true;
  // Single-knot instructions from which arrays and constants are addressed compactly;
  // 0: never.
  std::uint64_t compact_addressing_from = kCompactAddressingFrom;
  // A library without batched code (batch_width 1) whose every function is small, has no
  // lane pairs and uses only what the assembly back end prints is written as x86-64
  // assembly for this host (assembled and linked by the compiler driver, no C compiler
  // pass: builds in ~15 ms and ~6 MiB against ~100 ms and ~38 MiB). Needs a driver that
  // assembles AT&T syntax with AVX (gcc, clang: compilerAssembles) and a host with AVX2
  // and FMA. docs/code-generation.md, "The assembly back end".
  bool assembly = false;
};

struct SourceFile {
  std::string path;  // relative to the build directory
  std::string text;
};

// What was generated for one function.
struct GeneratedFunctionInfo {
  std::string name;
  std::uint32_t needed_nodes = 0;    // graph nodes the outputs reach
  std::uint32_t operations = 0;      // arithmetic statements (a sincos counts once)
  std::uint32_t sincos_pairs = 0;
  std::uint32_t max_locals = 0;      // most scalar locals of one part
  std::uint32_t parts = 1;           // translation units the body is spread over
  std::uint32_t transfer_slots = 0;  // work-buffer doubles (per lane) between parts
  std::uint32_t lane_pairs = 0;      // pairs of operations computed together (single-knot code)
};

struct GeneratedLibrary {
  std::vector<SourceFile> sources;  // .c files, each one translation unit
  std::vector<SourceFile> headers;  // files the sources include (abi.h); -I the build dir
  std::vector<GeneratedFunctionInfo> functions;
};

// The instructions `function`'s single-knot code issues for its operations, as
// generateLibrary(graph, {function}, options) lowers it: the operations, less one per
// lane pair (two operations in the lanes of one vector instruction). Lowers the function
// (no C is written). What the function builder compares two ways of building by.
std::uint64_t singleKnotInstructions(const symbolic::Graph& graph, const FunctionDefinition& function,
                                     const CodegenOptions& options);

// The library's sources: one file with every function's entry points and the
// descriptor, plus one file per part of each split function. Throws
// std::invalid_argument when a definition does not validate, or two share a name.
GeneratedLibrary generateLibrary(const symbolic::Graph& graph, const std::vector<FunctionDefinition>& functions,
                                 const CodegenOptions& options = {});

// The text of robodiff/codegen/abi.h this generator was built with (the sources include it).
const std::string& abiHeaderText();
// The sin-and-cos kernel generated code and the interpreter share (sincos_kernel.h).
const std::string& sincosKernelText();

// `value` as a C double literal that reads back exactly (e.g. "0.1", "2.0", "-1e-300",
// "INFINITY").
std::string cDoubleLiteral(double value);

}  // namespace robodiff::codegen
