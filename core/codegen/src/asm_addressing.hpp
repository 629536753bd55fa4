// Short memory operands for the assembly's body: the stack frame and the constant pool
// read through base registers (%rbp, %rbx) that point into them, so that the operands
// read most often take a one-byte displacement instead of four (and no index byte, as
// %rsp needs). The body is printed with tokens naming byte offsets into the frame or
// the pool; once all are known, each base's bias is chosen to cover the most reads,
// and the tokens become operands. Why: docs/assembly-backend.md ("Code size").
#pragma once

#include <optional>
#include <string>

namespace robodiff::codegen::detail {

std::string frameOperand(int offset);  // `offset` bytes into the frame (from %rsp at entry's end)
std::string poolOperand(int offset);   // `offset` bytes into the 16-byte constants' pool

// Where %rbp and %rbx point (bytes into the frame and the pool), where the text reads
// either at all.
struct BaseBiases {
  std::optional<int> frame, pool;
};
BaseBiases chooseBiases(const std::string& text);

// The text with its tokens replaced by operands relative to the bases.
std::string resolveOperands(const std::string& text, const BaseBiases& biases);

}  // namespace robodiff::codegen::detail
