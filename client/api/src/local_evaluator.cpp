#include "local_evaluator.hpp"

#include <optional>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "robodiff/runtime/function_layout.hpp"

namespace robodiff::client::detail {
namespace {

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
  // The same layout the server makes from the same descriptor (throws when the blocks do
  // not match the spec's outputs).
  const runtime::FunctionLayout blocks = runtime::FunctionLayout::fromDescriptor(d, spec);
  layout_.inputs = blocks.inputs;
  layout_.outputs = blocks.outputs;
  layout_.state = rpc::FunctionState::Ready;
  in_offsets_.assign(blocks.input_offsets.begin(), blocks.input_offsets.end() - 1);
  out_offsets_.assign(blocks.output_offsets.begin(), blocks.output_offsets.end() - 1);
  work_size_ = function_.workSize();
  eval_ = d.eval;
}

std::string LocalEvaluator::differenceFrom(const rpc::GetFunctionReply& other) const {
  return runtime::FunctionLayout::fromReply(layout_).differenceFrom(runtime::FunctionLayout::fromReply(other));
}

}  // namespace robodiff::client::detail
