// Warmup's targets (warmup_targets.hpp).
#include "robodiff/workers/warmup_targets.hpp"

#include <algorithm>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <thread>
#include <utility>

#include "robodiff/functions/function_spec.hpp"

namespace robodiff::workers {

namespace fs = std::filesystem;

unsigned defaultWarmupWorkers() { return std::clamp(std::thread::hardware_concurrency(), 1u, 2u); }

void checkWarmupInputs(const WarmupRequest& request, const std::string& urdf_label, const std::string& spec_label) {
  for (const std::string& urdf : request.urdf_paths)
    if (!fs::is_regular_file(urdf)) throw std::runtime_error(urdf_label + " " + urdf + ": no such file");
  for (const std::string& spec : request.spec_paths) {
    if (!fs::is_regular_file(spec)) throw std::runtime_error(spec_label + " " + spec + ": no such file");
    loadFunctionSpec(spec);  // throws SpecError naming the file, the field and the value
  }
}

std::vector<BuildTarget> warmupTargets(const WarmupRequest& request) {
  std::vector<BuildTarget> targets;
  std::set<std::pair<fs::path, fs::path>> seen;
  for (const std::string& urdf : request.urdf_paths)
    for (const std::string& spec : request.spec_paths) {
      if (!seen.emplace(fs::weakly_canonical(urdf), fs::weakly_canonical(spec)).second) continue;
      BuildTarget target;
      target.urdf_path = urdf;
      target.floating_base = request.floating_base;
      target.spec_path = spec;
      targets.push_back(std::move(target));
    }
  return targets;
}

}  // namespace robodiff::workers
