#include "local_evaluator.hpp"

#include <optional>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace robodiff::client::detail {
namespace {

rpc::OutputKind kindOf(robodiff::OutputKind kind) {
  switch (kind) {
    case robodiff::OutputKind::Value: return rpc::OutputKind::Value;
    case robodiff::OutputKind::Jacobian: return rpc::OutputKind::Jacobian;
    case robodiff::OutputKind::Hessian: return rpc::OutputKind::Hessian;
  }
  return rpc::OutputKind::Value;
}

// The index row's {"inputs": [...], "outputs": [...]} as expectations; unset when absent.
void expectSizes(const std::string& sizes_json, codegen::FunctionExpectations& expected) {
  if (sizes_json.empty()) return;
  const nlohmann::json sizes = nlohmann::json::parse(sizes_json, nullptr, false);
  if (!sizes.is_object()) return;
  auto read = [&](const char* key) -> std::optional<std::vector<std::uint32_t>> {
    const auto it = sizes.find(key);
    if (it == sizes.end() || !it->is_array()) return std::nullopt;
    std::vector<std::uint32_t> out;
    for (const auto& v : *it) {
      if (!v.is_number_unsigned()) return std::nullopt;
      out.push_back(v.get<std::uint32_t>());
    }
    return out;
  };
  expected.input_sizes = read("inputs");
  expected.output_sizes = read("outputs");
}

codegen::CompiledFunction openFunction(const cache::Artifact& artifact, const FunctionSpec& spec) {
  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(artifact.library());
  codegen::FunctionExpectations expected;
  expected.name = artifact.entry().info.function.empty() ? std::string(functionInfo(spec.function).name)
                                                         : artifact.entry().info.function;
  expectSizes(artifact.entry().info.sizes, expected);
  return library.function(expected);
}

}  // namespace

LocalEvaluator::LocalEvaluator(cache::Artifact artifact, const FunctionSpec& spec)
    : artifact_(std::move(artifact)), function_(openFunction(artifact_, spec)) {
  const robodiff_function_desc& d = function_.descriptor();
  if (d.n_outputs != spec.outputs.size())
    throw std::invalid_argument(artifact_.library().string() + ": the compiled function has " +
                                std::to_string(d.n_outputs) + " output blocks but the spec asks for " +
                                std::to_string(spec.outputs.size()));
  std::uint32_t offset = 0;
  for (std::uint32_t b = 0; b < d.n_inputs; ++b) {
    layout_.inputs.push_back({d.inputs[b].name, d.inputs[b].size});
    in_offsets_.push_back(offset);
    offset += d.inputs[b].size;
  }
  offset = 0;
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
    layout_.outputs.push_back(std::move(o));
    out_offsets_.push_back(offset);
    offset += b.nnz;
  }
  layout_.state = rpc::FunctionState::Ready;
  work_size_ = function_.workSize();
  eval_ = d.eval;
}

std::string LocalEvaluator::differenceFrom(const rpc::GetFunctionReply& other) const {
  const rpc::GetFunctionReply& mine = layout_;
  if (mine.inputs.size() != other.inputs.size())
    return std::to_string(mine.inputs.size()) + " input blocks against " + std::to_string(other.inputs.size());
  for (std::size_t b = 0; b < mine.inputs.size(); ++b)
    if (mine.inputs[b].name != other.inputs[b].name || mine.inputs[b].size != other.inputs[b].size)
      return "input block " + std::to_string(b) + ": " + mine.inputs[b].name + "[" +
             std::to_string(mine.inputs[b].size) + "] against " + other.inputs[b].name + "[" +
             std::to_string(other.inputs[b].size) + "]";
  if (mine.outputs.size() != other.outputs.size())
    return std::to_string(mine.outputs.size()) + " output blocks against " + std::to_string(other.outputs.size());
  for (std::size_t k = 0; k < mine.outputs.size(); ++k) {
    const rpc::OutputBlock& a = mine.outputs[k];
    const rpc::OutputBlock& b = other.outputs[k];
    const std::string where = "output block " + std::to_string(k) + " (" + a.name + ")";
    if (a.name != b.name) return where + ": named " + b.name + " by the server";
    if (a.rows != b.rows || a.cols != b.cols || a.nnz != b.nnz || a.layout != b.layout)
      return where + ": another shape or layout";
    if (a.row_offsets != b.row_offsets || a.col_indices != b.col_indices) return where + ": another sparsity pattern";
  }
  return {};
}

}  // namespace robodiff::client::detail
