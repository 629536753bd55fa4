#include "robodiff/runtime/function_layout.hpp"

#include <algorithm>
#include <stdexcept>

namespace robodiff::runtime {
namespace {

rpc::OutputKind kindOf(robodiff::OutputKind kind) {
  switch (kind) {
    case robodiff::OutputKind::Value: return rpc::OutputKind::Value;
    case robodiff::OutputKind::Jacobian: return rpc::OutputKind::Jacobian;
    case robodiff::OutputKind::Hessian: return rpc::OutputKind::Hessian;
  }
  return rpc::OutputKind::Value;
}

void requireOutputCount(std::size_t blocks, const FunctionSpec& spec, const char* where) {
  if (blocks != spec.outputs.size())
    throw std::invalid_argument(std::string(where) + " has " + std::to_string(blocks) +
                                " output blocks but the spec asks for " + std::to_string(spec.outputs.size()) +
                                " outputs");
}

// Offsets and totals from the block sizes.
void finish(FunctionLayout& layout) {
  layout.input_offsets.assign(1, 0);
  for (const rpc::InputBlock& b : layout.inputs) layout.input_offsets.push_back(layout.input_offsets.back() + b.size);
  layout.output_offsets.assign(1, 0);
  for (const rpc::OutputBlock& b : layout.outputs)
    layout.output_offsets.push_back(layout.output_offsets.back() + b.nnz);
  layout.input_count = layout.input_offsets.back();
  layout.output_count = layout.output_offsets.back();
}

}  // namespace

FunctionLayout FunctionLayout::fromDefinition(const codegen::FunctionDefinition& definition, const FunctionSpec& spec) {
  requireOutputCount(definition.outputs.size(), spec, "the traced function");
  FunctionLayout layout;
  for (const codegen::InputBlock& b : definition.inputs) layout.inputs.push_back({b.name, b.size});
  for (std::size_t k = 0; k < definition.outputs.size(); ++k) {
    const codegen::OutputBlock& b = definition.outputs[k];
    rpc::OutputBlock o;
    o.name = b.name;
    o.kind = kindOf(spec.outputs[k].kind);
    o.rows = b.rows;
    o.cols = b.cols;
    o.nnz = b.size();
    if (b.kind == codegen::OutputKind::Sparse) {
      o.layout = rpc::OutputLayout::SparseCsr;
      o.row_offsets = b.row_ptr;
      o.col_indices = b.col_idx;
    }
    layout.outputs.push_back(std::move(o));
  }
  finish(layout);
  return layout;
}

FunctionLayout FunctionLayout::fromDescriptor(const robodiff_function_desc& d, const FunctionSpec& spec) {
  requireOutputCount(d.n_outputs, spec, "the compiled library's function");
  FunctionLayout layout;
  for (std::uint32_t b = 0; b < d.n_inputs; ++b) layout.inputs.push_back({d.inputs[b].name, d.inputs[b].size});
  for (std::uint32_t k = 0; k < d.n_outputs; ++k) {
    const robodiff_output_desc& b = d.outputs[k];
    rpc::OutputBlock o;
    o.name = b.name;
    o.kind = kindOf(spec.outputs[k].kind);
    o.rows = b.rows;
    o.cols = b.cols;
    o.nnz = b.nnz;
    if (b.kind == ROBODIFF_OUTPUT_SPARSE) {
      o.layout = rpc::OutputLayout::SparseCsr;
      o.row_offsets.assign(b.row_ptr, b.row_ptr + b.rows + 1);
      o.col_indices.assign(b.col_idx, b.col_idx + b.nnz);
    }
    layout.outputs.push_back(std::move(o));
  }
  finish(layout);
  return layout;
}

FunctionLayout FunctionLayout::fromReply(const rpc::GetFunctionReply& reply) {
  FunctionLayout layout;
  layout.inputs = reply.inputs;
  layout.outputs = reply.outputs;
  finish(layout);
  return layout;
}

std::size_t FunctionLayout::inputBlockOf(std::uint32_t index) const {
  // upper_bound finds the first offset past index; the block starts one before it.
  const auto it = std::upper_bound(input_offsets.begin(), input_offsets.end(), index);
  return static_cast<std::size_t>(it - input_offsets.begin()) - 1;
}

std::string FunctionLayout::differenceFrom(const FunctionLayout& other) const {
  if (inputs.size() != other.inputs.size())
    return std::to_string(inputs.size()) + " input blocks against " + std::to_string(other.inputs.size());
  for (std::size_t b = 0; b < inputs.size(); ++b)
    if (inputs[b].name != other.inputs[b].name || inputs[b].size != other.inputs[b].size)
      return "input block " + std::to_string(b) + ": " + inputs[b].name + "[" + std::to_string(inputs[b].size) +
             "] against " + other.inputs[b].name + "[" + std::to_string(other.inputs[b].size) + "]";
  if (outputs.size() != other.outputs.size())
    return std::to_string(outputs.size()) + " output blocks against " + std::to_string(other.outputs.size());
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const rpc::OutputBlock& a = outputs[k];
    const rpc::OutputBlock& b = other.outputs[k];
    const std::string where = "output block " + std::to_string(k) + " (" + a.name + ")";
    if (a.name != b.name) return where + ": named " + b.name + " in the other";
    if (a.kind != b.kind) return where + ": another kind";
    if (a.rows != b.rows || a.cols != b.cols)
      return where + ": " + std::to_string(a.rows) + "x" + std::to_string(a.cols) + " against " +
             std::to_string(b.rows) + "x" + std::to_string(b.cols);
    if (a.layout != b.layout) return where + ": dense against sparse";
    if (a.nnz != b.nnz) return where + ": " + std::to_string(a.nnz) + " nonzeros against " + std::to_string(b.nnz);
    if (a.row_offsets != b.row_offsets || a.col_indices != b.col_indices) return where + ": another sparsity pattern";
  }
  return {};
}

}  // namespace robodiff::runtime
