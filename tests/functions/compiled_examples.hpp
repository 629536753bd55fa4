// Test support for tests/functions: the project's example robots (examples/robots) and
// example specs (examples/specs), each spec generated, compiled and loaded once per
// (robot, spec, optimisation) and shared by the tests of the folder.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>

#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

inline const Model& libraryArm7() {
  static const Model m = loadUrdfFile((sourceDir() / "examples/robots/arm7.urdf").string());
  return m;
}

inline const Model& quadruped() {
  static const Model m =
      loadUrdfFile((sourceDir() / "examples/robots/quadruped.urdf").string(), RootJoint::FreeFlyer);
  return m;
}

inline const Model& robot(const std::string& name) { return name == "arm7" ? libraryArm7() : quadruped(); }

// An example spec (examples/specs/NAME.json), to be compiled at `optimization`.
inline FunctionSpec exampleSpec(const std::string& name, const std::string& optimization = "O0") {
  FunctionSpec spec = loadFunctionSpec((sourceDir() / "examples/specs" / (name + ".json")).string());
  spec.build.optimization = optimization;
  return spec;
}

// A generated, compiled and loaded function. The directory outlives the library.
struct Compiled {
  TempDir dir;
  FunctionSpec spec;
  GeneratedFunctionLibrary generated;
  std::unique_ptr<codegen::LoadedLibrary> library;
  std::optional<codegen::CompiledFunction> function;

  const BuiltFunction& built() const { return generated.built; }
  const codegen::FunctionDefinition& definition() const { return generated.built.definition; }
};

inline std::unique_ptr<Compiled> compile(const Model& model, const FunctionSpec& spec, const LibraryOptions& options = {}) {
  auto c = std::make_unique<Compiled>();
  c->spec = spec;
  c->generated = generateFunctionLibrary(model, spec, c->dir.path() / "out", options);
  c->library = std::make_unique<codegen::LoadedLibrary>(codegen::LoadedLibrary::open(c->generated.library));
  c->function.emplace(c->library->function(c->definition().name));
  return c;
}

// Built once per (robot, spec, optimisation) with the default options and shared by the tests.
inline const Compiled& cached(const std::string& robot_name, const std::string& spec_name,
                       const std::string& optimization = "O0") {
  static std::map<std::string, std::unique_ptr<Compiled>> cache;
  std::unique_ptr<Compiled>& slot = cache[robot_name + "/" + spec_name + "/" + optimization];
  if (!slot) slot = compile(robot(robot_name), exampleSpec(spec_name, optimization));
  return *slot;
}

}  // namespace robodiff::testing
