#include "robodiff/functions/model_function.hpp"

namespace robodiff {

std::pair<int, int> valueShape(const Model& model, ModelFunction function) {
  switch (function) {
    case ModelFunction::Rnea:
    case ModelFunction::Aba:
    case ModelFunction::Gravity:
    case ModelFunction::Nle: return {model.nv, 1};
    case ModelFunction::Crba:
    case ModelFunction::Minv: return {model.nv, model.nv};
    case ModelFunction::Fk: return {3, 4};
    case ModelFunction::FrameJacobian: return {6, model.nv};
    case ModelFunction::Com: return {3, 1};
    case ModelFunction::Regressor: return {model.nv, 10 * model.njoints()};
  }
  throw std::logic_error("valueShape: unknown function");
}

int inputSize(const Model& model, const std::string& input) { return input == "q" ? model.nq : model.nv; }

int resolveFrame(const Model& model, const FunctionSpec& spec) {
  if (!functionInfo(spec.function).needs_frame) return -1;
  if (std::optional<int> f = model.findFrame(spec.frame)) return *f;
  std::string names;
  for (const Frame& f : model.frames) names += (names.empty() ? "" : ", ") + f.name;
  throw SpecError("frame: '" + spec.frame + "' is not a frame of " + (model.name.empty() ? "the model" : model.name) +
                  " (frames: " + names + ")");
}

}  // namespace robodiff
