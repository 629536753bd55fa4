#include "robodiff/cache/prepared_build.hpp"

#include <iterator>

#include "robodiff/cache/target_check.hpp"
#include "robodiff/codegen/compiler.hpp"

namespace robodiff::cache {
namespace {

const char* methodName(AbaJacobianMethod m) { return m == AbaJacobianMethod::Analytic ? "analytic" : "differentiate"; }
const char* methodName(RneaJacobianMethod m) {
  switch (m) {
    case RneaJacobianMethod::Analytic: return "analytic";
    case RneaJacobianMethod::Differentiate: return "differentiate";
    case RneaJacobianMethod::Cheaper: return "cheaper";
  }
  return "unknown";
}
const char* methodName(AbaValueMethod m) {
  switch (m) {
    case AbaValueMethod::Articulated: return "articulated";
    case AbaValueMethod::Factors: return "factors";
    case AbaValueMethod::Cheaper: return "cheaper";
  }
  return "unknown";
}

// The generator's version and every builder and codegen option that changes the code
// generated for the same model and spec (the C name included: it is in the library).
std::string generatorIdentity(const LibraryOptions& options, const std::string& c_name) {
  const FunctionBuilderOptions& b = options.builder;
  const codegen::CodegenOptions& c = options.codegen;
  return std::string(codegen::kGeneratorVersion) + "; name=" + c_name + "; aba_jacobian=" +
         methodName(b.aba_jacobian) + "; rnea_jacobian=" + methodName(b.rnea_jacobian) +
         "; aba_rnea_partials=" + methodName(b.aba_rnea_partials) + "; aba_value=" + methodName(b.aba_value) +
         "; jacobian_mode=" + symbolic::toString(b.jacobian_mode) + "; split=" + std::to_string(c.split_threshold) +
         "; reuse_temporaries=" + (c.reuse_temporaries ? "1" : "0") + "; batch_width=" + std::to_string(c.batch_width) +
         "; assembly=" + (c.assembly ? "1" : "0");
}

std::string spaceSeparated(const std::vector<std::string>& words) {
  std::string text;
  for (const auto& w : words) text += (text.empty() ? "" : " ") + w;
  return text;
}

// Everything prepareBuild prepares but the compiler's identity (which needs the compiler).
PreparedBuild prepareWithoutCompiler(const std::string& model_hash, const FunctionSpec& spec,
                                     const std::string& function_name, const std::string& compiler) {
  PreparedBuild p;
  if (!function_name.empty()) p.options.builder.name = function_name;
  p.options.compiler.compiler = compiler;
  p.options.model_hash = model_hash;
  // The C name buildFunction gives the function.
  const std::string c_name = function_name.empty() ? spec.functionName() : function_name;
  const codegen::CompilerOptions effective = compilerOptionsFor(spec.build, p.options.compiler);
  p.identity.model_hash = model_hash;
  p.identity.spec = normalizedSpecJson(spec);
  p.identity.generator = generatorIdentity(p.options, c_name);
  p.identity.flags = codegen::compilerFlags(effective);
  p.identity.target_cpu = targetCpuIdentity(spec.build.march_native, spec.build.target);
  p.info.function = c_name;
  p.info.portable_key = p.identity.portableKey();
  return p;
}

}  // namespace

std::string preparePortableKey(const std::string& model_hash, const FunctionSpec& spec,
                               const std::string& function_name) {
  return prepareWithoutCompiler(model_hash, spec, function_name, "").info.portable_key;
}

std::vector<std::string> portableKeysFor(const std::string& model_hash, const FunctionSpec& spec,
                                         const std::string& function_name) {
  std::vector<std::string> keys{preparePortableKey(model_hash, spec, function_name)};
  if (!spec.build.target.empty() || !spec.build.march_native) return keys;
  FunctionSpec for_level = spec;
  for_level.build.march_native = false;  // as parseFunctionSpec stores a level
  for (auto level = std::rbegin(kTargetLevels); level != std::rend(kTargetLevels); ++level) {
    if (!cpuSupportsLevel(*level)) continue;
    for_level.build.target = *level;
    keys.push_back(preparePortableKey(model_hash, for_level, function_name));
  }
  return keys;
}

PreparedBuild prepareBuild(const Model& model, const std::string& model_hash, const FunctionSpec& spec,
                           const std::string& function_name, const std::string& compiler) {
  PreparedBuild p = prepareWithoutCompiler(model_hash, spec, function_name, compiler);
  p.identity.compiler = codegen::compilerIdentity(compilerOptionsFor(spec.build, p.options.compiler));
  p.key = p.identity.key();

  p.info.model_hash = model_hash;
  p.info.robot = model.name;
  p.info.spec = p.identity.spec;
  p.info.compiler = p.identity.compiler + " " + spaceSeparated(p.identity.flags) +
                    " target=" + targetLabel(spec.build.march_native, spec.build.target);
  return p;
}

}  // namespace robodiff::cache
