// Names for the rows and columns of a function's output blocks, for the CSV header.
#include <algorithm>

#include "robodiff/batch/trajectory_table.hpp"

namespace robodiff::batch {

namespace {

// One label per tangent entry of each input differentiated against, in "wrt" order:
// "<input>_<joint>" for an input per joint (a configuration's nv tangent entries), else
// "<input>_<i>". Empty when an input is not among `inputs`.
std::vector<std::string> wrtLabels(const Model& model, const std::vector<std::string>& wrt,
                                   const std::vector<std::string>& configurations,
                                   const std::vector<BlockLayout>& inputs, const std::vector<std::string>& dofs) {
  std::vector<std::string> labels;
  for (const std::string& name : wrt) {
    const auto input = std::find_if(inputs.begin(), inputs.end(), [&](const BlockLayout& b) { return b.name == name; });
    if (input == inputs.end()) return {};
    const bool configuration = input->size == static_cast<std::uint32_t>(model.nq) &&
                               std::count(configurations.begin(), configurations.end(), name) > 0;
    if (configuration || input->size == dofs.size()) {
      for (const std::string& dof : dofs) labels.push_back(name + "_" + dof);
    } else {
      for (std::uint32_t i = 0; i < input->size; ++i) labels.push_back(name + "_" + std::to_string(i));
    }
  }
  return labels;
}

// The value's rows and columns that are the model's velocity coordinates, by function:
// torques and accelerations per joint, the mass matrix (and its inverse) both ways, a
// frame Jacobian's columns. Other values (fk, com, the regressor, a user function's
// outputs) are numbered: a size that happens to equal nv says nothing.
void valueAxes(ModelFunction function, const std::vector<std::string>& dofs, AxisLabels& axes) {
  switch (function) {
    case ModelFunction::Rnea:
    case ModelFunction::Aba:
    case ModelFunction::Gravity:
    case ModelFunction::Nle: axes.rows = dofs; break;
    case ModelFunction::Crba:
    case ModelFunction::Minv: axes.rows = axes.cols = dofs; break;
    case ModelFunction::FrameJacobian: axes.cols = dofs; break;
    default: break;
  }
}

}  // namespace

std::vector<AxisLabels> outputAxisLabels(const Model& model, const FunctionSpec& spec,
                                         const std::vector<BlockLayout>& inputs,
                                         const std::vector<BlockLayout>& outputs) {
  std::vector<AxisLabels> labels(outputs.size());
  if (spec.outputs.size() != outputs.size()) return labels;
  const std::vector<std::string> dofs = dofNames(model);
  const std::vector<std::string> configurations = configurationInputs(spec);
  AxisLabels value;  // the value's rows and columns, for the value and a Jacobian's rows
  if (!spec.isUser()) valueAxes(spec.function, dofs, value);
  for (std::size_t b = 0; b < outputs.size(); ++b) {
    const BlockLayout& block = outputs[b];
    AxisLabels& axes = labels[b];
    const OutputSpec& output = spec.outputs[b];
    std::vector<std::string> wrt = wrtLabels(model, output.wrt, configurations, inputs, dofs);
    if (output.kind == OutputKind::Value) {
      // A user function's gradient or vector-Jacobian product: one entry per wrt entry.
      if (!wrt.empty() && block.cols == 1 && wrt.size() == block.rows) axes.rows = std::move(wrt);
      if (value.rows.size() == block.rows) axes.rows = value.rows;
      if (value.cols.size() == block.cols) axes.cols = value.cols;
      continue;
    }
    if (wrt.size() != block.cols) continue;
    // A Jacobian's rows are the value's entries when the value is a vector per joint
    // (a matrix value's entries are numbered); a Hessian's rows are its columns.
    if (output.kind == OutputKind::Hessian) axes.rows = wrt;
    else if (value.cols.empty() && value.rows.size() == block.rows) axes.rows = value.rows;
    axes.cols = std::move(wrt);
  }
  return labels;
}

}  // namespace robodiff::batch
