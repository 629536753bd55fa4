// `robodiff bench --keep DIR --reuse`: a second timing round loads the libraries a first
// round built and kept in DIR instead of building them again (bench/anchors times two
// alternating rounds and measures the cold builds in the first).
#pragma once

#include <filesystem>
#include <optional>

#include "robodiff/functions/function_library.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::cli::bench {

// The library kept in `dir` (as generateFunctionLibrary(model, spec, dir, options) left
// it) when it is the one this build would make: the same normalised spec (build options
// included) and, source file by source file, the same generated C. The spec is traced
// and the C generated again (cheap); nothing is compiled. Nothing when any of it differs
// or is missing. The compile report keeps the compiler and flags the kept build recorded;
// its timings and sizes are not measured again (zero).
std::optional<GeneratedFunctionLibrary> keptLibrary(const Model& model, const FunctionSpec& spec,
                                                    const std::filesystem::path& dir, const LibraryOptions& options);

}  // namespace robodiff::cli::bench
