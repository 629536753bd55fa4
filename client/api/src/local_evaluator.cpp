#include "local_evaluator.hpp"

#include "robodiff/runtime/cached_function.hpp"
#include "robodiff/runtime/function_layout.hpp"

namespace robodiff::client::detail {
LocalEvaluator::LocalEvaluator(cache::Artifact artifact, const FunctionSpec& spec)
    : artifact_(std::move(artifact)), function_(runtime::openCachedFunction(artifact_, spec)) {
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
