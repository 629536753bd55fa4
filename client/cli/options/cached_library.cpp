// compute's generated backend through the cache (cached_library.hpp).
#include "options/cached_library.hpp"

#include <optional>
#include <stdexcept>

#include "options/cache_location.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/spec_check.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/runtime/cached_function.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/worker_pool.hpp"

namespace robodiff::cli {
namespace {

// Builds the key in `cache` in one robodiff-worker process, as warmup does. True when this
// call built it; false when another process had built it meanwhile (found on claiming).
bool buildIntoCache(cache::Cache& cache, const Model& model, const std::string& model_hash, const FunctionSpec& spec,
                    const CachedLibraryRequest& request) {
  const std::string robot = model.name.empty() ? request.urdf_source : model.name;
  workers::WorkerPool pool(workers::WorkerPoolOptions{});
  workers::CachedBuilderOptions options;
  options.compiler = request.compiler;
  workers::CachedBuilder builder(cache, pool, options);
  workers::BuildTarget target{request.urdf_source, request.floating_base, "<spec>", ""};
  target.urdf_text = request.urdf_text;
  target.model = std::make_shared<const Model>(model);  // a copy: cheaper than parsing again
  target.model_hash = model_hash;
  target.spec_text = specJson(spec);  // a spec the worker reads back (a user spec included)
  const workers::BuildStatus done = builder.buildAll({target}).at(0);
  if (done.state == workers::BuildState::Failed)
    throw std::runtime_error("building " + spec.functionName() + " for " + robot + " into the cache " +
                             cache.dir().string() + " failed: " + done.message);
  return done.state == workers::BuildState::Done;
}

// The library's blocks are the traced function's (same key, same function; this guards
// the buffers evaluateBlocks sizes from the trace). Throws codegen::LoadError naming the
// first difference.
void expectSameBlocks(const codegen::CompiledFunction& function, const codegen::FunctionDefinition& definition,
                      const std::string& key) {
  const robodiff_function_desc& d = function.descriptor();
  std::string problem;
  if (d.n_inputs != definition.inputs.size() || d.n_outputs != definition.outputs.size()) {
    problem = std::to_string(d.n_inputs) + " input and " + std::to_string(d.n_outputs) + " output blocks, not " +
              std::to_string(definition.inputs.size()) + " and " + std::to_string(definition.outputs.size());
  } else {
    for (std::size_t b = 0; b < definition.inputs.size() && problem.empty(); ++b)
      if (d.inputs[b].size != definition.inputs[b].size)
        problem = "input '" + definition.inputs[b].name + "' has " + std::to_string(d.inputs[b].size) + " entries";
    for (std::size_t b = 0; b < definition.outputs.size() && problem.empty(); ++b) {
      const codegen::OutputBlock& o = definition.outputs[b];
      if (d.outputs[b].rows != o.rows || d.outputs[b].cols != o.cols || d.outputs[b].nnz != o.size())
        problem = "output '" + o.name + "' is " + std::to_string(d.outputs[b].rows) + " x " +
                  std::to_string(d.outputs[b].cols) + " with " + std::to_string(d.outputs[b].nnz) + " entries";
    }
  }
  if (!problem.empty())
    throw codegen::LoadError("the cached library " + key + " does not match the function built here: " + problem +
                             " (remove it with `robodiff cache rm " + key + "`, or run with --no-cache)");
}

}  // namespace

CachedLibrary CachedLibrary::open(const Model& model, const SpecFunction& f, const CachedLibraryRequest& request,
                                  const std::function<void()>& on_building) {
  cache::Cache cache = openCliCache(request.cache_dir, "", true);
  const std::string model_hash = canonicalHash(model);
  const cache::PreparedBuild prepared = cache::prepareBuild(model, model_hash, f.spec(), "", request.compiler);
  // find() checks the library's SHA-256; a corrupt one is quarantined and reported a miss.
  std::optional<cache::Artifact> artifact = cache.find(prepared.key);
  bool hit = artifact.has_value();
  if (!artifact) {
    if (on_building) on_building();
    hit = !buildIntoCache(cache, model, model_hash, f.spec(), request);
    artifact = cache.find(prepared.key);
    if (!artifact)
      throw std::runtime_error("the build of " + f.spec().functionName() +
                               " finished but its library is not in the cache " + cache.dir().string());
  }
  codegen::CompiledFunction function = runtime::openCachedFunction(*artifact, f.spec());
  expectSameBlocks(function, f.definition(), artifact->key());
  return CachedLibrary(std::move(*artifact), std::move(function), hit);
}

std::vector<Eigen::MatrixXd> CachedLibrary::evaluate(const SpecFunction& f,
                                                     const std::vector<Eigen::VectorXd>& runtime) const {
  return specBlockMatrices(f.spec(), f.built(), evaluateBlocks(function_, f.definition(), runtime));
}

}  // namespace robodiff::cli
