#pragma once
// A function's blocks as GetFunction reports them and as evaluation uses them (by the
// server, and by a client evaluating a cached library in its own process): input
// blocks (name, size) and output blocks (kind, shape, dense or CSR layout), with each
// block's offset in the concatenated inputs / outputs of one knot.
//
// Made from a fresh trace (the builder's FunctionDefinition) or from a compiled
// library's descriptor (a cache hit); both carry the same blocks, and the kind of each
// output (value, Jacobian, Hessian) comes from the spec (one output block per spec
// output, in order), so the two are equal for the same function.

#include <cstdint>
#include <string>
#include <vector>

#include "robodiff/codegen/abi.h"
#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/schema/messages.hpp"

namespace robodiff::runtime {

struct FunctionLayout {
  std::vector<rpc::InputBlock> inputs;
  std::vector<rpc::OutputBlock> outputs;
  std::vector<std::uint32_t> input_offsets;   // inputs.size() + 1: block b is [off[b], off[b+1])
  std::vector<std::uint32_t> output_offsets;  // outputs.size() + 1
  std::uint32_t input_count = 0;              // doubles per knot in
  std::uint32_t output_count = 0;             // doubles per knot out

  // Throws std::invalid_argument when the blocks do not match the spec's outputs.
  static FunctionLayout fromDefinition(const codegen::FunctionDefinition& definition, const FunctionSpec& spec);
  static FunctionLayout fromDescriptor(const robodiff_function_desc& descriptor, const FunctionSpec& spec);
  // From what GetFunction returned (a client's view of a server's function).
  static FunctionLayout fromReply(const rpc::GetFunctionReply& reply);

  // The input block holding double `index` of a knot (index < input_count).
  std::size_t inputBlockOf(std::uint32_t index) const;

  // Empty when equal; otherwise what differs first, in words.
  std::string differenceFrom(const FunctionLayout& other) const;
};

}  // namespace robodiff::runtime
