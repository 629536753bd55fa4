#include "robodiff/functions/function_library.hpp"

#include <chrono>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "robodiff/model/canonical.hpp"

namespace robodiff {

namespace fs = std::filesystem;
using nlohmann::json;

codegen::CodegenOptions LibraryOptions::defaultCodegenOptions() {
  codegen::CodegenOptions o;
  // Parts of ~1,000 operations: compile time grows faster than linearly with the size of
  // a translation unit, and parts compile in parallel. Measured on 2 cores, Panda RNEA
  // value + Jacobian (7,853 operations, gcc -O2 -march=native): 6,000 -> 2 parts,
  // 1.25 s; 2,500 -> 4, 1.28 s; 1,000 -> 8, 0.89 s; 500 -> 16, 0.87 s; evaluation
  // 0.83-0.87 µs throughout (values cross parts through the work buffer, which stays in
  // L1). Talos RNEA + Jacobian (45k): 3,000 -> 18.6 s under load; 1,000 -> 4.5 s.
  o.split_threshold = 1000;
  o.assembly = true;  // where codegenOptionsFor and the function allow
  return o;
}

codegen::CompilerOptions compilerOptionsFor(const BuildOptions& build, codegen::CompilerOptions base) {
  using codegen::OptimizationLevel;
  const std::string& o = build.optimization;
  base.optimization = o == "O0"   ? OptimizationLevel::O0
                      : o == "O1" ? OptimizationLevel::O1
                      : o == "O3" ? OptimizationLevel::O3
                                  : OptimizationLevel::O2;
  base.native = build.march_native;
  base.march = build.target;
  base.fast_math = build.fast_math;
  return base;
}

codegen::CodegenOptions codegenOptionsFor(const BuildOptions& build, codegen::CodegenOptions base) {
  if (!build.batch) base.batch_width = 1;
  // Code for this CPU (-march=native) fits this CPU's instruction cache: with 64 KiB,
  // Panda's RNEA + J (5,700 instructions) ran 1.5% slower without compact addressing
  // and its ABA + J 3% faster, and both compiled 9-15% sooner.
  const bool this_cpu = build.march_native && build.target.empty();
  if (this_cpu && base.compact_addressing_from == codegen::kCompactAddressingFrom)
    base.compact_addressing_from = codegen::compactAddressingFrom(codegen::hostInstructionCacheBytes());
  const bool optimized = build.optimization == "O2" || build.optimization == "O3" || build.optimization.empty();
  if (build.batch || !this_cpu || build.fast_math || !optimized) base.assembly = false;
  return base;
}

codegen::CodegenOptions codegenOptionsFor(const BuildOptions& build, codegen::CodegenOptions base,
                                          const codegen::CompilerOptions& compiler) {
  base = codegenOptionsFor(build, std::move(base));
  if (base.assembly && !codegen::compilerAssembles(compiler)) base.assembly = false;
  return base;
}

namespace {

void writeFile(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary);
    f << text;
    if (!f.flush()) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, path);
}

}  // namespace

GeneratedFunctionLibrary generateFunctionLibrary(const Model& model, const FunctionSpec& spec, const fs::path& out_dir,
                                                 const LibraryOptions& options) {
  auto stage = [&](const char* name) {
    if (options.on_stage) options.on_stage(name);
  };
  GeneratedFunctionLibrary result;
  stage("trace");
  result.built = buildFunction(model, spec, options.builder);
  const std::string& name = result.built.definition.name;

  codegen::CompilerOptions compiler = compilerOptionsFor(spec.build, options.compiler);
  const codegen::CodegenOptions codegen = codegenOptionsFor(spec.build, options.codegen, compiler);
  const auto t_emit = std::chrono::steady_clock::now();
  const codegen::GeneratedLibrary sources = generateLibrary(*result.built.graph, {result.built.definition}, codegen);
  result.emit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_emit).count();
  result.info = sources.functions.at(0);
  for (const codegen::SourceFile& s : sources.sources) result.source_bytes += s.text.size();

  stage("compile");
  fs::create_directories(out_dir);
  if (compiler.jobs == 0) compiler.jobs = std::max(1u, std::thread::hardware_concurrency());
  compiler.build_dir = out_dir / "src";
  fs::remove_all(compiler.build_dir);  // sources of an earlier build must not linger beside these
  compiler.keep_build_dir = true;
  result.library = out_dir / (name + ".so");
  result.compile = codegen::compileLibrary(sources, result.library, compiler);
  result.library_bytes = fs::file_size(result.library);
  result.description = out_dir / (name + ".json");
  writeFile(result.description, describeFunction(model, spec, result.built, &result, options.model_hash) + "\n");
  return result;
}

std::string describeFunction(const Model& model, const FunctionSpec& spec, const BuiltFunction& built,
                             const GeneratedFunctionLibrary* generated, const std::string& model_hash) {
  json d;
  d["name"] = built.definition.name;
  d["model"] = {{"name", model.name}, {"nq", model.nq}, {"nv", model.nv}, {"hash", model_hash.empty() ? canonicalHash(model) : model_hash}};
  d["spec"] = json::parse(normalizedSpecJson(spec));
  json inputs = json::array();
  for (const codegen::InputBlock& b : built.definition.inputs) inputs.push_back({{"name", b.name}, {"size", b.size}});
  d["inputs"] = inputs;
  json outputs = json::array();
  for (std::size_t k = 0; k < built.outputs.size(); ++k) {
    const BuiltOutput& o = built.outputs[k];
    const codegen::OutputBlock& block = built.definition.outputs[k];
    json j = {{"name", o.name}, {"kind", toString(o.kind)}, {"rows", o.rows}, {"cols", o.cols}, {"nnz", o.nnz},
              {"layout", o.layout == Layout::Dense ? "dense" : "sparse"}};
    if (spec.user) j["user_kind"] = toString(spec.user->outputs[k].kind);
    if (o.kind != OutputKind::Value) j["wrt"] = o.wrt;
    if (o.kind == OutputKind::Hessian)
      j["triangle"] = o.layout == Layout::Dense ? "full symmetric matrix" : "lower triangle";
    if (block.kind == codegen::OutputKind::Sparse) j["row_ptr"] = block.row_ptr, j["col_idx"] = block.col_idx;
    outputs.push_back(j);
  }
  d["outputs"] = outputs;
  d["method"] = built.method;
  d["build"] = {{"trace_nodes", built.trace_nodes},
                {"function_nodes", built.graph->size()},
                {"trace_seconds", built.timings.trace_seconds},
                {"differentiate_seconds", built.timings.differentiate_seconds},
                {"assemble_seconds", built.timings.assemble_seconds}};
  if (built.rule_operations)  // a user function: what its primitives' derivative rules save
    d["derivative_operations"] = {{"with_primitive_rules", built.rule_operations},
                                  {"differentiating_primitive_traces", built.traced_operations}};
  if (generated) {
    json& b = d["build"];
    b["operations"] = generated->info.operations;
    b["parts"] = generated->info.parts;
    b["lane_pairs"] = generated->info.lane_pairs;
    b["emit_seconds"] = generated->emit_seconds;
    b["compile_seconds"] = generated->compile.seconds;
    b["compiler"] = generated->compile.compiler;
    b["flags"] = generated->compile.flags;
    b["peak_compiler_memory_bytes"] = generated->compile.peak_memory_bytes;
    b["source_bytes"] = generated->source_bytes;
    b["library_bytes"] = generated->library_bytes;
    b["library"] = generated->library.filename().string();
  }
  return d.dump(2);
}

}  // namespace robodiff
