#include "robodiff/runtime/cached_function.hpp"

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "robodiff/cache/target_check.hpp"

namespace robodiff::runtime {
namespace {

// The index row's {"inputs": [...], "outputs": [...]} as expectations; unset when absent.
void expectSizes(const std::string& sizes_json, codegen::FunctionExpectations& expected) {
  if (sizes_json.empty()) return;
  const nlohmann::json sizes = nlohmann::json::parse(sizes_json, nullptr, false);
  if (!sizes.is_object()) return;
  auto read = [&](const char* key) -> std::optional<std::vector<std::uint32_t>> {
    const auto it = sizes.find(key);
    if (it == sizes.end() || !it->is_array()) return std::nullopt;
    std::vector<std::uint32_t> out;
    for (const auto& v : *it) {
      if (!v.is_number_unsigned()) return std::nullopt;
      out.push_back(v.get<std::uint32_t>());
    }
    return out;
  };
  expected.input_sizes = read("inputs");
  expected.output_sizes = read("outputs");
}

}  // namespace

codegen::CompiledFunction openCachedFunction(const cache::Artifact& artifact, const FunctionSpec& spec) {
  // Before dlopen: a library for another CPU is refused, not run into SIGILL.
  if (const std::string problem = cache::targetProblem(artifact.entry().info.compiler); !problem.empty())
    throw codegen::LoadError("cache entry " + artifact.entry().key + " cannot run on this CPU: " + problem);
  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(artifact.library());
  codegen::FunctionExpectations expected;
  expected.name = artifact.entry().info.function.empty() ? spec.functionName()
                                                         : artifact.entry().info.function;
  expectSizes(artifact.entry().info.sizes, expected);
  return library.function(expected);
}

}  // namespace robodiff::runtime
