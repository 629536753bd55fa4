// A spec's function, built once and evaluated in the ways the CLI offers:
// - reference: the value from core/dynamics in double (referenceValue), derivatives
//   from the builder's graph evaluated node by node (symbolic::Graph::evaluate), no
//   code generation or interpreter involved; for a user function, the double
//   evaluation of its expressions and central finite differences of it
//   (userReferenceOutputs: the derivatives are approximations);
// - interpreted: the builder's graph run by codegen::Interpreter;
// - generated: C code generated and compiled into a temporary directory, loaded, run.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/function_library.hpp"

namespace robodiff::cli {

enum class Backend { Reference, Generated, Interpreted };

const std::vector<std::string>& backendNames();  // reference, generated, interpreted
Backend parseBackend(const std::string& name);
const char* toString(Backend backend);

// A fresh directory temp_directory_path()/robodiff-XXXXXX, removed with its contents
// when this goes out of scope.
class TemporaryDirectory {
 public:
  TemporaryDirectory();
  ~TemporaryDirectory();
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// generateFunctionLibrary with errors a user can act on: a compile failure carries what
// the compiler printed, a graph over the node limit says so.
GeneratedFunctionLibrary generateLibrary(const Model& model, const FunctionSpec& spec,
                                         const std::filesystem::path& out_dir, const LibraryOptions& options = {});

class SpecFunction {
 public:
  // Builds the function (`model` must outlive this); compiles and loads it only when `backends` includes Generated
  // (in a temporary directory, removed once the library is loaded).
  SpecFunction(const Model& model, FunctionSpec spec, const std::vector<Backend>& backends,
               const LibraryOptions& options = {});

  const FunctionSpec& spec() const { return spec_; }
  const BuiltFunction& built() const { return built_; }
  const codegen::FunctionDefinition& definition() const { return built_.definition; }

  // Every output block at the runtime inputs (one vector per input block of
  // definition(): the variable inputs, then "weights" if a Hessian takes them), as
  // matrices: the value rows x cols, Jacobians m x n, Hessians full and symmetric.
  std::vector<Eigen::MatrixXd> evaluate(Backend backend, const std::vector<Eigen::VectorXd>& runtime) const;

  // All inputs of the model function (fixed ones from the spec), for the reference.
  std::vector<Eigen::VectorXd> allInputs(const std::vector<Eigen::VectorXd>& runtime) const;
  // The weights of output `k` (a Hessian): fixed in the spec or the runtime block.
  Eigen::VectorXd hessianWeights(std::size_t k, const std::vector<Eigen::VectorXd>& runtime) const;
  // The value, flattened row-major, as a rows x cols matrix.
  Eigen::MatrixXd valueMatrix(const Eigen::VectorXd& flat) const;

 private:
  std::vector<Eigen::MatrixXd> evaluateReference(const std::vector<Eigen::VectorXd>& runtime) const;

  const Model& model_;
  FunctionSpec spec_;
  BuiltFunction built_;
  std::optional<codegen::Interpreter> interpreter_;
  std::optional<codegen::CompiledFunction> compiled_;  // keeps its library loaded
};

}  // namespace robodiff::cli
