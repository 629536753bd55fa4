// The assembly back end: a library of single-knot functions as one x86-64 assembly
// file, which the compiler driver only assembles and links (no C compiler pass).
//
// Where it applies: x86-64 with AVX2 and FMA, functions of additions, subtractions,
// products, quotients, square roots, absolute values and sin-cos pairs (the robot
// functions' value rows), with at most seven input and output blocks. Everything else
// is C (c_emitter.hpp). Why and what it measured: docs/code-generation.md.
#pragma once

#include <optional>
#include <vector>

#include "asm_registers.hpp"
#include "lane_pairs.hpp"
#include "robodiff/codegen/c_emitter.hpp"

namespace robodiff::codegen::detail {

// Functions of this many instructions (operations less lane pairs) or more are C.
// Measured (direct calls, the median of 5 processes): up to 17,987 instructions the
// assembly ran 1-10% faster than C (Solo-12's ABA + J, RNEA + J; the Panda's ABA + J,
// Euler step + J; Talos's ABA and Euler step values); from 26,880 1-4% slower (Talos's
// RNEA + J and ABA + J, the free-flying Talos's RNEA + J). docs/assembly-backend.md.
inline constexpr std::uint32_t kAssemblyBelow = 20000;

// The host's target for the assembly, or nullopt where it does not apply (not x86-64,
// or no AVX2 and FMA).
std::optional<AsmTarget> hostAsmTarget();

// The library as assembly (one source, library.s), or nullopt when a function needs
// what only C prints or has kAssemblyBelow instructions or more. A function's lane pairs
// (C's choice, options.lane_pairs) are computed by packed instructions. eval_batch
// loops over eval (batch width 1).
// `pairings`: each function's (lane_pairs.hpp), when the caller found them; else found here.
std::optional<GeneratedLibrary> generateAssemblyLibrary(const symbolic::Graph& graph,
                                                        const std::vector<FunctionDefinition>& functions,
                                                        const CodegenOptions& options, const AsmTarget& target,
                                                        std::vector<FunctionPairing>* pairings = nullptr);

}  // namespace robodiff::codegen::detail
