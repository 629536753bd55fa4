// A spec's model function evaluated on any scalar: double for the reference, the
// symbolic scalar for tracing. One place maps a ModelFunction to the core/dynamics call,
// its inputs and the shape of its value.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/functions/function_spec.hpp"

namespace robodiff {

// rows x cols of the function's value (a vector is n x 1).
std::pair<int, int> valueShape(const Model& model, ModelFunction function);

// The size of one input of the function: q has nq entries, v / a / tau nv.
int inputSize(const Model& model, const std::string& input);

// The frame a spec names (fk, frame_jacobian), or -1 when the function needs none.
// Throws SpecError naming the frame and listing the frames there are.
int resolveFrame(const Model& model, const FunctionSpec& spec);

// The value of the function at `inputs` (every input of the function, in its order),
// row-major in a rows x cols matrix.
template <class S>
MatX<S> modelFunctionValue(const Model& model, Data<S>& data, const FunctionSpec& spec, int frame,
                           const std::vector<VecX<S>>& inputs) {
  auto in = [&](std::size_t k) -> const VecX<S>& { return inputs.at(k); };
  switch (spec.function) {
    case ModelFunction::Rnea: return rnea(model, data, in(0), in(1), in(2));
    case ModelFunction::Aba: return aba(model, data, in(0), in(1), in(2));
    case ModelFunction::Crba: return crba(model, data, in(0));
    case ModelFunction::Gravity: return computeGeneralizedGravity(model, data, in(0));
    case ModelFunction::Nle: return nonLinearEffects(model, data, in(0), in(1));
    case ModelFunction::Fk: {
      forwardKinematics(model, data, in(0));
      const SE3<S> oMf = framePlacement(model, data, frame);
      MatX<S> m(3, 4);
      m.template leftCols<3>() = oMf.rotation;
      m.col(3) = oMf.translation;
      return m;
    }
    case ModelFunction::FrameJacobian: return computeFrameJacobian(model, data, in(0), frame, spec.reference);
    case ModelFunction::Com: return centerOfMass(model, data, in(0));
    case ModelFunction::Regressor: return jointTorqueRegressor(model, data, in(0), in(1), in(2));
    case ModelFunction::Minv: return computeMinverse(model, data, in(0));
  }
  throw std::logic_error("modelFunctionValue: unknown function");
}

}  // namespace robodiff
