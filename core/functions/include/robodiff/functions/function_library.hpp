// A spec and a model to a loadable library on disk: build the function (trace,
// differentiate, assemble), emit C, compile it, and describe it in JSON. One call does
// what `robodiff generate` does; the cache and the build workers use the same steps.
//
// Directory layout written by generateFunctionLibrary(out_dir):
//   <name>.so    the library (abi.h's self-describing descriptor inside)
//   <name>.json  the description (describeFunction)
//   src/         the C sources and abi.h, as compiled
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/functions/function_builder.hpp"

namespace robodiff {

struct LibraryOptions {
  FunctionBuilderOptions builder;
  codegen::CodegenOptions codegen = defaultCodegenOptions();
  // Compiler, limits and jobs. The optimisation level, -march=native and -ffast-math
  // come from the spec's build options (compilerOptionsFor), not from here.
  codegen::CompilerOptions compiler;
  // canonicalHash(model) when the caller has it (hashed once where the model was loaded);
  // empty: the description computes it.
  std::string model_hash;
  // Told each step as it starts: "trace" (build the function), then "compile" (emit C done,
  // compiler running). Build workers report it as progress.
  std::function<void(const char* stage)> on_stage;

  static codegen::CodegenOptions defaultCodegenOptions();
};

// The compiler options a spec's build section asks for, on top of `base`.
codegen::CompilerOptions compilerOptionsFor(const BuildOptions& build, codegen::CompilerOptions base = {});
// The code generator's options likewise ("batch": false, no SIMD batched code). The
// assembly back end stays on only for single-knot builds for this CPU at -O2 or -O3
// without -ffast-math (the assembly is neither of the other choices).
codegen::CodegenOptions codegenOptionsFor(const BuildOptions& build, codegen::CodegenOptions base);
// The same for a build by `compiler`: the assembly needs a driver that assembles it.
codegen::CodegenOptions codegenOptionsFor(const BuildOptions& build, codegen::CodegenOptions base,
                                          const codegen::CompilerOptions& compiler);

struct GeneratedFunctionLibrary {
  BuiltFunction built;
  codegen::GeneratedFunctionInfo info;  // operations, parts, ...
  codegen::CompileReport compile;
  double emit_seconds = 0;
  std::uintmax_t source_bytes = 0, library_bytes = 0;
  std::filesystem::path library, description;
};

// Builds, emits and compiles into out_dir (created if needed). Throws SpecError,
// symbolic::GraphTooLarge, codegen::CompileError.
GeneratedFunctionLibrary generateFunctionLibrary(const Model& model, const FunctionSpec& spec,
                                                 const std::filesystem::path& out_dir,
                                                 const LibraryOptions& options = {});

// The JSON description of a built function: the model (name, nq, nv, canonical hash),
// the normalised spec, input blocks, output blocks (shape, layout, nnz, CSR pattern of
// sparse blocks), how it was built, and the generation figures when given.
std::string describeFunction(const Model& model, const FunctionSpec& spec, const BuiltFunction& built,
                             const GeneratedFunctionLibrary* generated = nullptr, const std::string& model_hash = {});

}  // namespace robodiff
