// compute's generated backend from a library kept by `robodiff bench --keep DIR`: DIR/<row>
// holds <row>.json (its spec and build), <row>.so and src/. It is loaded only when it is
// the library this build would make (bench::keptLibrary: the same normalised spec and the
// same generated C; nothing is compiled), so checking it checks what bench timed.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "options/function_backends.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::cli {

// f's outputs by the library kept in `dir`. Throws std::invalid_argument naming `dir` and
// what is wrong: no kept library (or several), or one that is not this build's.
std::vector<Eigen::MatrixXd> evaluateKeptLibrary(const Model& model, const SpecFunction& f,
                                                 const std::filesystem::path& dir,
                                                 const std::vector<Eigen::VectorXd>& runtime);

}  // namespace robodiff::cli
