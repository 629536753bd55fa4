// TrajectoryFunctions: inverse dynamics with its Jacobian, and its weighted Hessian.
#include "robodiff/batch/trajectory_optimization_functions.hpp"

#include <future>
#include <mutex>

namespace robodiff::batch {

FunctionSpec TrajectoryFunctions::firstOrderSpec() {
  return parseFunctionSpec(R"({"function": "rnea", "outputs": [{"kind": "value"},
                               {"kind": "jacobian", "wrt": ["q", "v", "a"], "layout": "dense"}]})",
                           "trajectory optimisation (first order)");
}

FunctionSpec TrajectoryFunctions::secondOrderSpec() {
  return parseFunctionSpec(R"({"function": "rnea", "outputs": [
                               {"kind": "hessian", "wrt": ["q", "v", "a"], "weights": "input", "layout": "sparse"}]})",
                           "trajectory optimisation (second order)");
}

TrajectoryFunctions TrajectoryFunctions::open(const Model& model, const std::string& urdf_text,
                                              const BatchFunctionOptions& options) {
  if (options.backend != Backend::Compiled) {
    BatchFunction first = BatchFunction::open(model, urdf_text, false, firstOrderSpec(), options);
    BatchFunction second = BatchFunction::open(model, urdf_text, false, secondOrderSpec(), options);
    return TrajectoryFunctions(std::move(first), std::move(second));
  }
  // Compiled: both builds at once (each through its own worker; the cache serialises
  // what must be), progress told one at a time.
  BatchFunctionOptions shared = options;
  auto progress_mutex = std::make_shared<std::mutex>();
  if (options.on_progress)
    shared.on_progress = [progress_mutex, tell = options.on_progress](const std::string& what) {
      std::lock_guard lock(*progress_mutex);
      tell(what);
    };
  std::future<BatchFunction> second = std::async(std::launch::async, [&] {
    return BatchFunction::open(model, urdf_text, false, secondOrderSpec(), shared);
  });
  BatchFunction first = BatchFunction::open(model, urdf_text, false, firstOrderSpec(), shared);
  return TrajectoryFunctions(std::move(first), second.get());
}

}  // namespace robodiff::batch
