#include "commands/bench_kept_library.hpp"

#include <fstream>
#include <iterator>

#include <nlohmann/json.hpp>

#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/function_spec.hpp"

namespace robodiff::cli::bench {

namespace fs = std::filesystem;

namespace {

std::optional<std::string> readWhole(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The kept description's build record, when its spec is `spec`'s.
std::optional<nlohmann::json> keptBuild(const fs::path& description, const FunctionSpec& spec) {
  const std::optional<std::string> text = readWhole(description);
  if (!text) return std::nullopt;
  const nlohmann::json d = nlohmann::json::parse(*text, nullptr, false);
  if (d.is_discarded() || !d.contains("spec") || !d.contains("build")) return std::nullopt;
  if (d["spec"] != nlohmann::json::parse(normalizedSpecJson(spec))) return std::nullopt;
  return d["build"];
}

}  // namespace

std::optional<GeneratedFunctionLibrary> keptLibrary(const Model& model, const FunctionSpec& spec, const fs::path& dir,
                                                    const LibraryOptions& options) {
  GeneratedFunctionLibrary kept;
  kept.built = buildFunction(model, spec, options.builder);
  const std::string& name = kept.built.definition.name;
  kept.library = dir / (name + ".so");
  kept.description = dir / (name + ".json");
  const std::optional<nlohmann::json> build = keptBuild(kept.description, spec);
  if (!build || !fs::is_regular_file(kept.library)) return std::nullopt;
  const codegen::GeneratedLibrary sources =
      codegen::generateLibrary(*kept.built.graph, {kept.built.definition}, codegenOptionsFor(spec.build, options.codegen));
  for (const codegen::SourceFile& s : sources.sources)
    if (readWhole(dir / "src" / s.path) != s.text) return std::nullopt;
  kept.info = sources.functions.at(0);
  kept.compile.library = kept.library;
  kept.compile.compiler = build->value("compiler", "");
  kept.compile.flags = build->value("flags", std::vector<std::string>{});
  kept.library_bytes = fs::file_size(kept.library);
  return kept;
}

}  // namespace robodiff::cli::bench
