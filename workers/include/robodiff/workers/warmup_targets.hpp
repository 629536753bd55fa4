#pragma once
// What a warmup builds (`robodiff warmup`, robodiff.warmup in Python): every robot with
// every spec, as CachedBuilder targets, after checking what a person fixes by hand.
#include <string>
#include <vector>

#include "robodiff/workers/cached_builder.hpp"

namespace robodiff::workers {

struct WarmupRequest {
  std::vector<std::string> urdf_paths, spec_paths;
  bool floating_base = false;
};

// Missing files and specs that do not parse are reported before anything is built:
// throws std::runtime_error "<urdf_label> PATH: no such file" (likewise for specs), or
// SpecError naming the spec file, the field and the value. A URDF that does not load is
// left to the builder (a failed target that says why).
void checkWarmupInputs(const WarmupRequest& request, const std::string& urdf_label = "urdf",
                       const std::string& spec_label = "spec");

// Worker processes a warmup runs at once by default: the cores, at most 2 (each
// compiler can take a core and a few hundred MiB).
unsigned defaultWarmupWorkers();

// The cross product, robot-major; a (robot, spec) pair named twice (the same files) once.
std::vector<BuildTarget> warmupTargets(const WarmupRequest& request);

}  // namespace robodiff::workers
