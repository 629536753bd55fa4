// A library kept by `robodiff bench --keep DIR` (DIR/<row> holds <row>.json, its spec and
// build; <row>.so; and src/), used again only when it is the library this build would make:
// the same normalised spec (build options included) and, source file by source file, the
// same generated C. bench --reuse times it again without building; compute --kept
// evaluates it, so checking it checks what bench timed.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <vector>

#include "options/function_backends.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::cli {

// The library kept in `dir` (as generateFunctionLibrary(model, spec, dir, options) left
// it) when it is the one this build would make. The spec is traced and the C generated
// again (cheap); nothing is compiled. Nothing when any of it differs or is missing. The
// compile report keeps the compiler and flags the kept build recorded; its timings and
// sizes are not measured again (zero).
std::optional<GeneratedFunctionLibrary> keptLibrary(const Model& model, const FunctionSpec& spec,
                                                    const std::filesystem::path& dir, const LibraryOptions& options);

// f's outputs by the library kept in `dir` (its one <name>.json beside <name>.so). Throws
// std::invalid_argument naming `dir` and what is wrong: no kept library (or several), or
// one that is not this build's.
std::vector<Eigen::MatrixXd> evaluateKeptLibrary(const Model& model, const SpecFunction& f,
                                                 const std::filesystem::path& dir,
                                                 const std::vector<Eigen::VectorXd>& runtime);

}  // namespace robodiff::cli
