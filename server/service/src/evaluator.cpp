#include "evaluator.hpp"

#include "robodiff/runtime/cached_function.hpp"

namespace robodiff::server::detail {

std::shared_ptr<const CompiledEvaluator> loadCompiled(const cache::Artifact& artifact, const FunctionSpec& spec) {
  codegen::CompiledFunction function = runtime::openCachedFunction(artifact, spec);
  FunctionLayout layout = FunctionLayout::fromDescriptor(function.descriptor(), spec);
  return std::make_shared<const CompiledEvaluator>(std::move(layout), artifact, std::move(function));
}

}  // namespace robodiff::server::detail
