#include "robodiff/cache/target_check.hpp"

#include "robodiff/cache/cache_key.hpp"

namespace robodiff::cache {

bool cpuSupportsLevel(const std::string& level) {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  __builtin_cpu_init();
  if (level == "x86-64-v2") return __builtin_cpu_supports("x86-64-v2");
  if (level == "x86-64-v3") return __builtin_cpu_supports("x86-64-v3");
  if (level == "x86-64-v4") return __builtin_cpu_supports("x86-64-v4");
#else
  (void)level;
#endif
  return false;
}

std::string targetProblem(const std::string& entry_compiler) {
  const std::string marker = " target=";
  const auto at = entry_compiler.rfind(marker);
  if (at == std::string::npos) return {};
  const std::string label = entry_compiler.substr(at + marker.size());
  if (label == "generic") return {};
  if (label.rfind("native:", 0) == 0) {
    if (label == targetLabel(true)) return {};
    return "it was built with -march=native on another CPU (" + label + "; this CPU is " + targetLabel(true) +
           ")";
  }
  if (label.rfind("x86-64-v", 0) == 0) {
    if (cpuSupportsLevel(label)) return {};
    return "it was built for " + label + ", which this CPU does not support";
  }
  return "it was built for an unknown target '" + label + "'";
}

}  // namespace robodiff::cache
