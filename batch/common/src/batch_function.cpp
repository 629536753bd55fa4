// BatchFunction: a spec built for a model, compiled from the cache or interpreted, and
// evaluated over many knots on all cores.
#include "robodiff/batch/batch_function.hpp"

#include <algorithm>
#include <atomic>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/runtime/cached_function.hpp"
#include "robodiff/runtime/function_layout.hpp"
#include "robodiff/workers/build_job.hpp"
#include "robodiff/workers/cached_builder.hpp"
#include "robodiff/workers/worker_pool.hpp"

namespace robodiff::batch {

const char* toString(Backend backend) { return backend == Backend::Compiled ? "compiled" : "interpreted"; }

Backend parseBackend(const std::string& text) {
  if (text == "compiled" || text == "generated") return Backend::Compiled;
  if (text == "interpreted") return Backend::Interpreted;
  throw std::invalid_argument("backend '" + text + "' is not one of compiled, interpreted");
}

struct BatchFunction::Impl {
  Backend backend = Backend::Compiled;
  std::vector<BlockLayout> inputs, outputs;
  std::size_t input_count = 0, output_count = 0;
  unsigned threads = 1;

  // Compiled: the function (keeps its library loaded) and the pinned artifact.
  std::optional<codegen::CompiledFunction> compiled;
  std::optional<cache::Artifact> artifact;
  // Interpreted: the graph the interpreter was made from is not needed after construction.
  std::optional<codegen::Interpreter> interpreter;

  std::size_t workSize() const { return compiled ? compiled->workSize() : interpreter->workSize(); }
  std::size_t batchWorkSize() const { return compiled ? compiled->batchWorkSize() : interpreter->workSize(); }
  std::uint32_t batchWidth() const { return compiled ? std::max<std::uint32_t>(compiled->batchWidth(), 1) : 1; }

  // One knot, input and output blocks at their offsets in the knot's doubles.
  void evaluateOne(const double* in, double* out, double* work) const {
    constexpr std::size_t kSmall = 16;  // more blocks than this: pointer arrays on the heap
    const double* in_small[kSmall];
    double* out_small[kSmall];
    std::vector<const double*> in_big;
    std::vector<double*> out_big;
    const double** ip = in_small;
    double** op = out_small;
    if (inputs.size() > kSmall) ip = (in_big.resize(inputs.size()), in_big.data());
    if (outputs.size() > kSmall) op = (out_big.resize(outputs.size()), out_big.data());
    for (std::size_t b = 0; b < inputs.size(); ++b) ip[b] = in + inputs[b].offset;
    for (std::size_t b = 0; b < outputs.size(); ++b) op[b] = out + outputs[b].offset;
    if (compiled)
      compiled->evaluate(ip, op, work);
    else
      interpreter->evaluate(ip, op, work);
  }

  // Knots [begin, end). The batched entry point wants each block's knots contiguous
  // (block-major), so chunks of knots are transposed into scratch and back.
  void evaluateRange(std::uint64_t begin, std::uint64_t end, const double* in, double* out,
                     std::vector<double>& work, std::vector<double>& in_scratch, std::vector<double>& out_scratch) const {
    const std::uint32_t width = batchWidth();
    if (!compiled || width <= 1 || end - begin < width) {
      for (std::uint64_t k = begin; k < end; ++k) evaluateOne(in + k * input_count, out + k * output_count, work.data());
      return;
    }
    // Chunks of at most 16 batch widths.
    const std::uint64_t max_chunk = std::uint64_t{width} * 16;
    in_scratch.resize(max_chunk * input_count);
    out_scratch.resize(max_chunk * output_count);
    std::vector<const double*> ip(inputs.size());
    std::vector<double*> op(outputs.size());
    for (std::uint64_t k0 = begin; k0 < end; k0 += max_chunk) {
      const std::uint64_t n = std::min(max_chunk, end - k0);
      for (std::size_t b = 0; b < inputs.size(); ++b) {
        const BlockLayout& block = inputs[b];
        double* dst = in_scratch.data() + block.offset * n;
        for (std::uint64_t k = 0; k < n; ++k)
          std::copy_n(in + (k0 + k) * input_count + block.offset, block.size, dst + k * block.size);
        ip[b] = dst;
      }
      for (std::size_t b = 0; b < outputs.size(); ++b) op[b] = out_scratch.data() + outputs[b].offset * n;
      compiled->evaluateBatch(n, ip.data(), op.data(), work.data());
      for (std::size_t b = 0; b < outputs.size(); ++b) {
        const BlockLayout& block = outputs[b];
        const double* src = op[b];
        for (std::uint64_t k = 0; k < n; ++k)
          std::copy_n(src + k * block.size, block.size, out + (k0 + k) * output_count + block.offset);
      }
    }
  }
};

namespace {

void setLayout(BatchFunction::Impl& impl, const runtime::FunctionLayout& layout) {
  for (std::size_t b = 0; b < layout.inputs.size(); ++b) {
    BlockLayout block;
    block.name = layout.inputs[b].name;
    block.rows = layout.inputs[b].size;
    block.cols = 1;
    block.size = layout.inputs[b].size;
    block.offset = layout.input_offsets[b];
    impl.inputs.push_back(std::move(block));
  }
  for (std::size_t b = 0; b < layout.outputs.size(); ++b) {
    const rpc::OutputBlock& o = layout.outputs[b];
    BlockLayout block;
    block.name = o.name;
    block.rows = o.rows;
    block.cols = o.cols;
    block.sparse = o.layout == rpc::OutputLayout::SparseCsr;
    block.size = o.nnz;
    block.offset = layout.output_offsets[b];
    block.row_ptr = o.row_offsets;
    block.col_idx = o.col_indices;
    impl.outputs.push_back(std::move(block));
  }
  impl.input_count = layout.input_count;
  impl.output_count = layout.output_count;
}

void openCompiled(BatchFunction::Impl& impl, const Model& model, const std::string& urdf_text, bool floating_base,
                  const FunctionSpec& spec, const BatchFunctionOptions& options) {
  auto tell = [&](const std::string& what) {
    if (options.on_progress) options.on_progress(what);
  };
  cache::Cache cache = cache::Cache::open(options.cache_dir.empty() ? cache::defaultCacheDir() : options.cache_dir);
  const std::string model_hash = canonicalHash(model);
  const cache::PreparedBuild prepared = cache::prepareBuild(model, model_hash, spec, "", options.compiler);
  std::optional<cache::Artifact> artifact = cache.find(prepared.key);
  if (artifact) {
    tell("cached");
  } else {
    tell("building");
    workers::WorkerPoolOptions pool_options;
    pool_options.worker_executable = options.worker_executable;
    workers::WorkerPool pool(pool_options);
    workers::CachedBuilderOptions builder_options;
    builder_options.compiler = options.compiler;
    workers::CachedBuilder builder(cache, pool, builder_options);
    workers::BuildTarget target{"<urdf>", floating_base, "<spec>", ""};
    target.urdf_text = urdf_text;
    target.model = std::make_shared<const Model>(model);  // a copy: cheaper than parsing again
    target.model_hash = model_hash;
    target.spec_text = specJson(spec);  // a user spec's normalised JSON is a key, not a spec
    const std::vector<workers::BuildStatus> done = builder.buildAll({target});
    if (done.at(0).state == workers::BuildState::Failed)
      throw std::runtime_error("building " + spec.functionName() + " for " + model.name +
                               " failed: " + done[0].message);
    artifact = cache.find(prepared.key);
    if (!artifact)
      throw std::runtime_error("the build of " + spec.functionName() +
                               " finished but its library is not in the cache " + cache.dir().string());
    tell("built");
  }
  impl.compiled = runtime::openCachedFunction(*artifact, spec);
  impl.artifact = std::move(artifact);
  setLayout(impl, runtime::FunctionLayout::fromDescriptor(impl.compiled->descriptor(), spec));
}

}  // namespace

BatchFunction BatchFunction::open(const Model& model, const std::string& urdf_text, bool floating_base,
                                  const FunctionSpec& spec, const BatchFunctionOptions& options) {
  auto impl = std::make_shared<Impl>();
  impl->backend = options.backend;
  impl->threads = options.threads != 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  if (options.backend == Backend::Compiled) {
    openCompiled(*impl, model, urdf_text, floating_base, spec, options);
  } else {
    BuiltFunction built = buildFunction(model, spec);
    setLayout(*impl, runtime::FunctionLayout::fromDefinition(built.definition, spec));
    impl->interpreter.emplace(*built.graph, built.definition);
  }
  return BatchFunction(std::move(impl));
}

Backend BatchFunction::backend() const { return impl_->backend; }
const std::vector<BlockLayout>& BatchFunction::inputs() const { return impl_->inputs; }
const std::vector<BlockLayout>& BatchFunction::outputs() const { return impl_->outputs; }
std::size_t BatchFunction::inputCount() const { return impl_->input_count; }
std::size_t BatchFunction::outputCount() const { return impl_->output_count; }

const BlockLayout& BatchFunction::input(const std::string& name) const {
  for (const BlockLayout& b : impl_->inputs)
    if (b.name == name) return b;
  throw std::out_of_range("the function has no input block '" + name + "'");
}

const BlockLayout& BatchFunction::output(const std::string& name) const {
  for (const BlockLayout& b : impl_->outputs)
    if (b.name == name) return b;
  throw std::out_of_range("the function has no output block '" + name + "'");
}

void BatchFunction::evaluate(const double* in, double* out) const {
  thread_local std::vector<double> work;
  if (work.size() < impl_->workSize()) work.resize(impl_->workSize());
  impl_->evaluateOne(in, out, work.data());
}

std::uint64_t BatchFunction::evaluateMany(std::uint64_t knots, const double* in, double* out,
                                          const std::function<bool()>& cancelled,
                                          const std::function<void(std::uint64_t done)>& progress) const {
  const Impl& f = *impl_;
  // Pieces of a few hundred knots, taken by the threads in turn: cancellation and
  // progress are seen between pieces.
  const std::uint64_t piece = std::max<std::uint64_t>(std::uint64_t{f.batchWidth()} * 32, 64);
  const std::uint64_t pieces = (knots + piece - 1) / piece;
  std::atomic<std::uint64_t> next{0}, done{0};
  std::atomic<bool> stop{false};
  std::mutex progress_mutex;
  auto worker = [&] {
    std::vector<double> work(std::max(f.workSize(), f.batchWorkSize()) + 1), in_scratch, out_scratch;
    for (;;) {
      if (stop.load()) return;
      if (cancelled && cancelled()) {
        stop = true;
        return;
      }
      const std::uint64_t p = next.fetch_add(1);
      if (p >= pieces) return;
      const std::uint64_t begin = p * piece, end = std::min(knots, begin + piece);
      f.evaluateRange(begin, end, in, out, work, in_scratch, out_scratch);
      const std::uint64_t now = done.fetch_add(end - begin) + (end - begin);
      if (progress) {
        std::lock_guard lock(progress_mutex);
        progress(now);
      }
    }
  };
  const unsigned threads = static_cast<unsigned>(std::min<std::uint64_t>(f.threads, std::max<std::uint64_t>(pieces, 1)));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  return done.load();
}

}  // namespace robodiff::batch
