#include "output/user_spec_output.hpp"

#include <stdexcept>

#include "output/output_table.hpp"
#include "robodiff/functions/reference.hpp"

namespace robodiff::cli {
namespace {

// A value with one column, a gradient, a vector-Jacobian product (n x 1).
bool isVectorOutput(const UserOutput& o, const Eigen::MatrixXd& m) {
  const bool vector_kind =
      o.kind == UserOutputKind::Value || o.kind == UserOutputKind::Gradient || o.kind == UserOutputKind::Vjp;
  return vector_kind && m.cols() == 1;
}

// The labels of input `name`'s tangent coordinates (the columns it takes in a derivative).
std::vector<std::string> tangentLabels(const Model& model, const NamedInput& in) {
  const int size = in.configuration ? model.nv : in.size;
  std::vector<std::string> labels;
  if (size == model.nv) {
    for (const std::string& joint : velocityLabels(model)) labels.push_back(in.name + ":" + joint);
    return labels;
  }
  for (int i = 0; i < size; ++i) labels.push_back(in.name + "[" + std::to_string(i) + "]");
  return labels;
}

// The labels of the columns of a derivative w.r.t. `wrt`, in order.
std::vector<std::string> wrtLabels(const Model& model, const std::vector<NamedInput>& inputs,
                                   const std::vector<std::string>& wrt) {
  std::vector<std::string> labels;
  for (const std::string& name : wrt)
    for (const NamedInput& in : inputs)
      if (in.name == name)
        for (std::string& label : tangentLabels(model, in)) labels.push_back(std::move(label));
  return labels;
}

}  // namespace

std::vector<NamedInput> userNamedInputs(const FunctionSpec& spec,
                                        const std::vector<std::pair<std::string, int>>& blocks) {
  std::vector<NamedInput> inputs;
  for (const auto& [name, size] : blocks) {
    const UserInput* in = spec.user->input(name);
    inputs.push_back({name, size, in && in->kind == UserInput::Kind::Configuration});
  }
  return inputs;
}

std::pair<std::vector<Eigen::VectorXd>, std::string> loadUserInputs(const StateArgs& args, const Model& model,
                                                                    const FunctionSpec& spec,
                                                                    const std::vector<NamedInput>& inputs) {
  if (args.seed)
    return {randomRuntimeInputs(model, spec, *args.seed), "random state (seed " + std::to_string(*args.seed) + ")"};
  if (!args.path.empty()) return {readNamedInputs(args.path, model, inputs), args.path};
  throw std::invalid_argument("--state FILE or --random-state SEED is required");
}

nlohmann::json userOutputsJson(nlohmann::json meta, const FunctionSpec& spec, const std::vector<Eigen::MatrixXd>& out) {
  for (std::size_t k = 0; k < out.size() && k < spec.user->outputs.size(); ++k) {
    const UserOutput& o = spec.user->outputs[k];
    if (meta.contains(o.name))
      throw std::invalid_argument("output '" + o.name + "' has the name of a key the JSON output already has (" +
                                  meta.dump() + "); rename the output");
    meta[o.name] = isVectorOutput(o, out[k]) ? toJson(Eigen::VectorXd(out[k].col(0))) : toJson(out[k]);
  }
  return meta;
}

void printUserTables(std::ostream& os, const Model& model, const FunctionSpec& spec,
                     const std::vector<NamedInput>& inputs, const std::vector<Eigen::MatrixXd>& out) {
  for (std::size_t k = 0; k < out.size() && k < spec.user->outputs.size(); ++k) {
    const UserOutput& o = spec.user->outputs[k];
    if (k) os << "\n";
    const std::string title = o.name + " (" + toString(o.kind) + " of " + o.of + ")";
    const std::vector<std::string> columns = wrtLabels(model, inputs, o.wrt);
    switch (o.kind) {
      case UserOutputKind::Value:
        if (out[k].cols() == 1) Table::vector(title, {}, out[k].col(0)).print(os);
        else Table::matrix(title, {}, out[k]).print(os);
        break;
      case UserOutputKind::Gradient:  // n x 1, one row per wrt coordinate
      case UserOutputKind::Vjp:
        Table::vector(title, columns, out[k].col(0)).print(os);
        break;
      case UserOutputKind::Jacobian:
        Table::matrix(title, {}, out[k], columns).print(os);
        break;
      case UserOutputKind::Hessian:
        Table::matrix(title, columns, out[k], columns).print(os);
        break;
    }
  }
}

}  // namespace robodiff::cli
