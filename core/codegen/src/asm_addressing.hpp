// Short memory operands for a large function's body: the stack frame and the constant
// pool read through base registers (%rbp, %rbx) that point into them, so that the operands
// read most often take a one-byte displacement instead of four (and no index byte, as
// %rsp needs). The body is printed with tokens naming byte offsets into the frame or
// the pool; once all are known, each base's bias is chosen to cover the most reads,
// and the tokens become operands. Why: docs/assembly-backend.md ("Code size").
#pragma once

#include <cstddef>
#include <optional>
#include <string>

namespace robodiff::codegen::detail {

// Functions of fewer operations read the frame from %rsp and the constants RIP-relative
// (their code fits the instruction caches: the bases' three instructions each way cost
// more than the bytes save). Measured: the Panda's RNEA value, CRBA, ABA value 0.1-0.4
// ns slower with the bases; Talos's RNEA value and CRBA (2,542 and 1,529 instructions)
// within 0.5%; its ABA value (4,848) 680 -> 623 ns.
inline constexpr std::size_t kBasesFrom = 3000;

std::string frameOperand(int offset);  // `offset` bytes into the frame (from %rsp at entry's end)
std::string poolOperand(int offset);   // `offset` bytes into the 16-byte constants' pool

// Where %rbp and %rbx point (bytes into the frame and the pool), where the text reads
// either at all; none: operands from %rsp and RIP-relative.
struct BaseBiases {
  std::optional<int> frame, pool;
};
BaseBiases chooseBiases(const std::string& text);

// The text with its tokens replaced by operands relative to the bases.
std::string resolveOperands(const std::string& text, const BaseBiases& biases);

}  // namespace robodiff::codegen::detail
