// Fuzz target: the URDF loader as robodiffd's LoadModel runs it (server/service/src/
// model_loading.cpp): the size/depth/count scan (urdf_limits), urdfdom's parser, the
// model built from it, the physics check (PhysicsCheck::Dynamic), then the canonical hash.
// A model that loads also runs RNEA and ABA once at the neutral configuration, the first
// thing a client asks of it.
//
// Expected failures are exceptions (ModelError and the like: LoadModel answers
// INVALID_ARGUMENT or RESOURCE_EXHAUSTED); what the fuzzer looks for is a crash, a
// sanitizer report, a hang or a leak.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>

#include "robodiff/dynamics/aba.hpp"
#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/rnea.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace {

// The server's limits, with a smaller size: the fuzzer's inputs are short anyway.
robodiff::UrdfLimits fuzzLimits() {
  robodiff::UrdfLimits limits;
  limits.max_bytes = 1 << 20;
  return limits;
}

void exerciseModel(const robodiff::Model& model) {
  (void)robodiff::canonicalHash(model);
  if (model.nv > 64) return;  // enough: bigger trees only repeat the same code
  robodiff::Data<double> data(model);
  const Eigen::VectorXd q = robodiff::neutralConfiguration(model);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.nv);
  (void)robodiff::rnea(model, data, q, zero, zero);
  (void)robodiff::aba(model, data, q, zero, zero);
}

void load(const std::string& urdf, robodiff::RootJoint root) {
  try {
    const robodiff::Model model =
        robodiff::loadUrdfString(urdf, root, "fuzz.urdf", fuzzLimits(), robodiff::PhysicsCheck::Dynamic);
    exerciseModel(model);
  } catch (const std::exception&) {
    // refused with a message: the expected outcome for most inputs
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string urdf(reinterpret_cast<const char*>(data), size);
  load(urdf, robodiff::RootJoint::Fixed);
  load(urdf, robodiff::RootJoint::FreeFlyer);
  return 0;
}
