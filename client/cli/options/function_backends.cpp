#include "options/function_backends.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/functions/spec_check.hpp"

namespace robodiff::cli {

namespace fs = std::filesystem;

const std::vector<std::string>& backendNames() {
  static const std::vector<std::string> names = {"reference", "generated", "interpreted"};
  return names;
}

Backend parseBackend(const std::string& name) {
  if (name == "reference") return Backend::Reference;
  if (name == "generated") return Backend::Generated;
  if (name == "interpreted") return Backend::Interpreted;
  throw std::invalid_argument("unknown backend '" + name + "' (reference, generated or interpreted)");
}

const char* toString(Backend backend) {
  switch (backend) {
    case Backend::Reference:
      return "reference";
    case Backend::Generated:
      return "generated";
    case Backend::Interpreted:
      return "interpreted";
  }
  return "?";
}

TemporaryDirectory::TemporaryDirectory() {
  std::string pattern = (fs::temp_directory_path() / "robodiff-XXXXXX").string();
  if (!::mkdtemp(pattern.data()))
    throw std::runtime_error("cannot create a temporary directory " + pattern + ": " + std::strerror(errno));
  path_ = pattern;
}

TemporaryDirectory::~TemporaryDirectory() {
  std::error_code ignored;  // a destructor must not throw; a leftover directory is harmless
  fs::remove_all(path_, ignored);
}

namespace {

// Runs `step` (a build or a generation), turning a compile failure and a graph over the
// node limit into messages a user can act on.
template <class Step>
auto explainingErrors(Step&& step) -> decltype(step()) {
  try {
    return step();
  } catch (const codegen::CompileError& e) {
    std::string message = std::string("compiling the generated code failed: ") + e.what();
    const std::string& output = e.compilerOutput();
    if (!output.empty() && message.find(output) == std::string::npos) message += "\ncompiler output:\n" + output;
    throw std::runtime_error(message);
  } catch (const symbolic::GraphTooLarge& e) {
    throw std::runtime_error(std::string("the function is too large to build: ") + e.what() +
                             "; ask for fewer outputs or derivatives, or use a smaller robot");
  }
}

}  // namespace

GeneratedFunctionLibrary generateLibrary(const Model& model, const FunctionSpec& spec, const fs::path& out_dir,
                                         const LibraryOptions& options) {
  return explainingErrors([&] { return generateFunctionLibrary(model, spec, out_dir, options); });
}

SpecFunction::SpecFunction(const Model& model, FunctionSpec spec, const std::vector<Backend>& backends,
                           const LibraryOptions& options)
    : model_(model), spec_(std::move(spec)) {
  auto uses = [&](Backend b) { return std::find(backends.begin(), backends.end(), b) != backends.end(); };
  if (uses(Backend::Generated)) {
    const TemporaryDirectory dir;
    GeneratedFunctionLibrary generated = generateLibrary(model_, spec_, dir.path(), options);
    // Once loaded, the library stays mapped when its file is removed with the directory.
    compiled_.emplace(codegen::LoadedLibrary::open(generated.library).function(generated.built.definition.name));
    built_ = std::move(generated.built);
  } else {
    built_ = explainingErrors([&] { return buildFunction(model_, spec_, options.builder); });
  }
  if (uses(Backend::Interpreted)) interpreter_.emplace(*built_.graph, built_.definition);
}

std::vector<Eigen::VectorXd> SpecFunction::allInputs(const std::vector<Eigen::VectorXd>& runtime) const {
  return specAllInputs(spec_, built_, runtime);
}

Eigen::VectorXd SpecFunction::hessianWeights(std::size_t k, const std::vector<Eigen::VectorXd>& runtime) const {
  return specHessianWeights(spec_, built_, k, runtime);
}

Eigen::MatrixXd SpecFunction::valueMatrix(const Eigen::VectorXd& flat) const { return specValueMatrix(built_, flat); }

std::vector<Eigen::MatrixXd> SpecFunction::evaluate(Backend backend,
                                                    const std::vector<Eigen::VectorXd>& runtime) const {
  std::vector<Eigen::VectorXd> blocks;
  switch (backend) {
    case Backend::Reference:
      return evaluateReference(runtime);
    case Backend::Interpreted:
      if (!interpreter_) throw std::logic_error("SpecFunction: built without the interpreter");
      blocks = evaluateBlocks(*interpreter_, definition(), runtime);
      break;
    case Backend::Generated:
      if (!compiled_) throw std::logic_error("SpecFunction: built without the generated library");
      blocks = evaluateBlocks(*compiled_, definition(), runtime);
      break;
  }
  return specBlockMatrices(spec_, built_, blocks);
}

std::vector<Eigen::MatrixXd> SpecFunction::evaluateReference(const std::vector<Eigen::VectorXd>& runtime) const {
  // The graph's inputs are numbered across the input blocks in order.
  std::vector<double> inputs;
  for (const Eigen::VectorXd& block : runtime) inputs.insert(inputs.end(), block.data(), block.data() + block.size());
  if (inputs.size() != definition().inputCount())
    throw std::invalid_argument(definition().name + " takes " + std::to_string(definition().inputCount()) +
                                " input numbers, " + std::to_string(inputs.size()) + " given");
  // A user function's reference is the double evaluation of its expressions and central
  // differences of it, already in the blocks' layout.
  if (spec_.isUser()) return userReferenceOutputs(model_, spec_, allInputs(runtime));
  std::vector<Eigen::MatrixXd> out;
  for (std::size_t k = 0; k < spec_.outputs.size(); ++k) {
    const OutputKind kind = spec_.outputs[k].kind;
    if (kind == OutputKind::Value) {
      out.push_back(valueMatrix(referenceValue(model_, spec_, allInputs(runtime))));
      continue;
    }
    const codegen::OutputBlock& block = definition().outputs[k];
    const std::vector<double> values = built_.graph->evaluate(block.values, inputs);
    out.push_back(
        blockMatrix(block, Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size())),
                    kind == OutputKind::Hessian));
  }
  return out;
}

}  // namespace robodiff::cli
