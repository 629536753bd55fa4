#pragma once
// Where a robot host's libraries come from before it compiles any itself (docs/fleet.md):
// the build hosts of its fleet. The service hands a function it has just traced (and
// serves with the interpreter) to its ArtifactSource; the source asks the build hosts,
// verifies what arrives and files it in this host's cache, and the service then loads it
// from there like any cached library. server/fleet implements it over DDS.

#include <functional>
#include <string>

#include "robodiff/cache/cache.hpp"
#include "robodiff/schema/messages.hpp"

namespace robodiff {
struct FunctionSpec;  // robodiff/functions/function_spec.hpp (kept out of the service's headers: Eigen)
}

namespace robodiff::server {

// One function's library, as the robot would build it.
struct ArtifactOrder {
  std::string function_id;  // names it in logs
  std::string model_hash;   // canonicalHash of the model
  std::string urdf;         // the URDF text the model was loaded from
  bool floating_base = false;
  const FunctionSpec* spec = nullptr;  // as the client asked for it (the source sets the target)
};

struct ArtifactDelivery {
  std::string key;      // the library's key in this host's cache; empty: none delivered
  std::string message;  // none delivered: why (every build host's answer)
  bool delivered() const { return !key.empty(); }
};

class ArtifactSource {
 public:
  virtual ~ArtifactSource() = default;
  // Blocks until the library is verified and filed in `cache` (its key), or until no
  // build host can deliver it (why). Returns early, undelivered, once `cancelled` is true.
  virtual ArtifactDelivery fetch(const ArtifactOrder& order, cache::Cache& cache,
                                 const std::function<bool()>& cancelled) = 0;
  // The robot's side of FleetStatus: its target, its build hosts and the counts.
  virtual rpc::FleetFigures figures() const = 0;
};

}  // namespace robodiff::server
