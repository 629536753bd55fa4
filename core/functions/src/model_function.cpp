#include "robodiff/functions/model_function.hpp"

#include "robodiff/language/bounded_text.hpp"
#include "robodiff/language/suggest.hpp"

namespace robodiff {
namespace {
constexpr std::size_t kFrameListBytes = 600;  // the frame list in an unknown-frame message
}  // namespace

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
  std::vector<std::string> names;
  for (const Frame& f : model.frames) names.push_back(f.name);
  std::string hint = language::didYouMean(spec.frame, names);
  if (hint.empty()) {  // no close name: list the frames, the list itself bounded
    std::string list;
    for (const std::string& name : names) list += (list.empty() ? "" : ", ") + language::boundedText(name);
    hint = " (frames: " + language::boundedText(list, kFrameListBytes) + ")";
  }
  throw SpecError("frame: " + language::quote(spec.frame) + " is not a frame of " +
                  (model.name.empty() ? std::string("the model") : language::boundedText(model.name)) + hint);
}

}  // namespace robodiff
