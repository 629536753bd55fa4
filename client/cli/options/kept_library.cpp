#include "options/kept_library.hpp"

#include <stdexcept>

#include "commands/bench_kept_library.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/spec_check.hpp"

namespace robodiff::cli {
namespace {

namespace fs = std::filesystem;

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

std::vector<Eigen::MatrixXd> evaluateKeptLibrary(const Model& model, const SpecFunction& f, const fs::path& dir,
                                                 const std::vector<Eigen::VectorXd>& runtime) {
  LibraryOptions options;
  options.builder.name = keptName(dir);
  const std::optional<GeneratedFunctionLibrary> kept = bench::keptLibrary(model, f.spec(), dir, options);
  if (!kept)
    throw std::invalid_argument("--kept " + dir.string() + ": " + options.builder.name +
                                " is not the library this spec and robot build (another spec, robot, build option "
                                "or generator version, or a changed source)");
  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(kept->library);
  const codegen::CompiledFunction function = library.function(options.builder.name);
  return specBlockMatrices(f.spec(), f.built(), evaluateBlocks(function, f.definition(), runtime));
}

}  // namespace robodiff::cli
