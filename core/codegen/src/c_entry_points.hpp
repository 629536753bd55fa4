// What a generated library has around its functions' bodies: the batched entry point of
// each function and the descriptor tables the ABI (abi.h) reads.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "robodiff/codegen/function_definition.hpp"

namespace robodiff::codegen::detail {

// The parameters of every single-knot entry point and part.
extern const char* const kEvalParams;

// `s` as a C string literal (quotes, backslashes and non-printable bytes escaped).
std::string cString(const std::string& s);

// `prefix`_eval_batch: n knots, RD_W at a time through `prefix`_chunk where the target
// has vector types, the rest (or everything) through `prefix`_eval.
std::string batchEntry(const FunctionDefinition& f, const std::string& prefix, std::uint32_t transfer);

// "const rd_pair_u `name` = rd_beyond_pair(in[b][i], in[b][j]) | ...;": all ones in a
// lane where one of `angles` (block, index) is beyond the sin-cos kernels' range.
std::string beyondRangeMask(const std::string& name,
                            const std::vector<std::pair<std::uint32_t, std::uint32_t>>& angles);

// `prefix`_eval of a function whose sin-cos kernels all take inputs: the arguments'
// range checked once, then `prefix`_in_range (kernels without checks) or, with one
// beyond the kernels' range, `prefix`_exact (libm for it). `angles`: (block, index).
std::string rangeCheckedEntry(const std::string& prefix,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& angles);

// The function's input and output descriptors (and a sparse block's CSR pattern).
std::string descriptorTables(const FunctionDefinition& f, const std::string& prefix);

}  // namespace robodiff::codegen::detail
