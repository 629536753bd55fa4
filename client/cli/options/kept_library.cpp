#include "options/kept_library.hpp"

#include <fstream>
#include <iterator>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/functions/spec_check.hpp"

namespace robodiff::cli {

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

// The name of the one library kept in dir: the stem of its <name>.json beside <name>.so.
std::string keptName(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw std::invalid_argument("--kept " + dir.string() + ": not a directory");
  std::vector<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".json" && fs::is_regular_file(fs::path(e.path()).replace_extension(".so")))
      names.push_back(e.path().stem().string());
  if (names.size() == 1) return names[0];
  std::string listed;
  for (const std::string& n : names) listed += (listed.empty() ? "" : ", ") + n;
  throw std::invalid_argument("--kept " + dir.string() + ": " +
                              (names.empty() ? std::string("no kept library (<name>.json beside <name>.so)")
                                             : "several kept libraries (" + listed + "): name one's directory"));
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
      codegen::generateLibrary(*kept.built.graph, {kept.built.definition},
                               codegenOptionsFor(spec.build, options.codegen, compilerOptionsFor(spec.build, options.compiler)));
  for (const codegen::SourceFile& s : sources.sources)
    if (readWhole(dir / "src" / s.path) != s.text) return std::nullopt;
  kept.info = sources.functions.at(0);
  kept.compile.library = kept.library;
  kept.compile.compiler = build->value("compiler", "");
  kept.compile.flags = build->value("flags", std::vector<std::string>{});
  kept.library_bytes = fs::file_size(kept.library);
  return kept;
}

std::vector<Eigen::MatrixXd> evaluateKeptLibrary(const Model& model, const SpecFunction& f, const fs::path& dir,
                                                 const std::vector<Eigen::VectorXd>& runtime) {
  LibraryOptions options;
  options.builder.name = keptName(dir);
  const std::optional<GeneratedFunctionLibrary> kept = keptLibrary(model, f.spec(), dir, options);
  if (!kept)
    throw std::invalid_argument("--kept " + dir.string() + ": " + options.builder.name +
                                " is not the library this spec and robot build (another spec, robot, build option "
                                "or generator version, or a changed source)");
  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(kept->library);
  const codegen::CompiledFunction function = library.function(options.builder.name);
  return specBlockMatrices(f.spec(), f.built(), evaluateBlocks(function, f.definition(), runtime));
}

}  // namespace robodiff::cli
