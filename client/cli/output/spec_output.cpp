#include "output/spec_output.hpp"

#include <stdexcept>

#include "output/output_table.hpp"
#include "robodiff/functions/model_function.hpp"

namespace robodiff::cli {

nlohmann::json toJson(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json toJson(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

std::vector<std::string> velocityLabels(const Model& model) {
  static const char* ff[] = {".vx", ".vy", ".vz", ".wx", ".wy", ".wz"};
  std::vector<std::string> labels;
  for (const Joint& j : model.joints)
    for (int k = 0; k < j.nv; ++k) labels.push_back(j.nv == 1 ? j.name : j.name + ff[k]);
  return labels;
}

void addStateOptions(CLI::App& cmd, StateArgs& args) {
  auto* state = cmd.add_option("--state", args.path,
                               "State JSON {\"q\": [...], \"v\": [...], \"a\": [...], \"tau\": [...]}; a spec's "
                               "Hessian with runtime weights reads \"weights\": [...] (one per value entry); a user spec "
                               "reads its variable inputs by name");
  auto* random = cmd.add_option("--random-state", args.seed,
                                "Use a random state (and random Hessian weights) drawn with this seed");
  state->excludes(random);
}

std::pair<State, std::string> loadState(const StateArgs& args, const Model& model, int weight_count) {
  if (args.seed)
    return {randomState(model, *args.seed, weight_count), "random state (seed " + std::to_string(*args.seed) + ")"};
  if (!args.path.empty()) return {readStateFile(args.path), args.path};
  throw std::invalid_argument("--state FILE or --random-state SEED is required");
}

nlohmann::json specOutputsJson(const std::string& label, const std::string& backend, const Model& model,
                               const FunctionSpec& spec, const std::vector<OutputBlockInfo>& blocks,
                               const std::vector<Eigen::MatrixXd>& out) {
  nlohmann::json j = {{"function", label}, {"backend", backend}, {"nq", model.nq}, {"nv", model.nv}};
  if (functionInfo(spec.function).needs_frame) j["frame"] = spec.frame;
  if (spec.function == ModelFunction::FrameJacobian) j["reference"] = toString(spec.reference);
  for (std::size_t k = 0; k < out.size() && k < blocks.size(); ++k) {
    const bool vector = blocks[k].kind == OutputKind::Value && out[k].cols() == 1;
    j[blocks[k].name] = vector ? toJson(Eigen::VectorXd(out[k].col(0))) : toJson(out[k]);
  }
  return j;
}

namespace {

// Row labels of the value: joints for per-joint vectors and matrices, else indices.
std::vector<std::string> valueRowLabels(ModelFunction f, const Model& model) {
  switch (f) {
    case ModelFunction::FrameJacobian: return {"vx", "vy", "vz", "wx", "wy", "wz"};
    case ModelFunction::Com: return {"x", "y", "z"};
    case ModelFunction::Fk: return {};
    default: return velocityLabels(model);
  }
}

// One label per tangent coordinate of the inputs `wrt`, e.g. "q:joint1", "v:joint1".
std::vector<std::string> tangentLabels(const std::vector<std::string>& wrt, const Model& model) {
  std::vector<std::string> labels;
  for (const std::string& w : wrt)
    for (const std::string& joint : velocityLabels(model)) labels.push_back(w + ":" + joint);
  return labels;
}

}  // namespace

void printSpecTables(std::ostream& os, const Model& model, const FunctionSpec& spec,
                     const std::vector<OutputBlockInfo>& blocks, const std::vector<Eigen::MatrixXd>& out) {
  const std::vector<std::string> value_rows = valueRowLabels(spec.function, model);
  // Matrices with a column per velocity coordinate: M, M^-1, a frame Jacobian.
  const bool per_joint_columns = spec.function == ModelFunction::Crba || spec.function == ModelFunction::Minv ||
                                 spec.function == ModelFunction::FrameJacobian;
  const std::vector<std::string> value_columns = per_joint_columns ? velocityLabels(model) : std::vector<std::string>{};
  // Derivative rows are the value's entries: labelled when the value is a vector.
  const int value_cols = valueShape(model, spec.function).second;
  const std::vector<std::string> derivative_rows = value_cols == 1 ? value_rows : std::vector<std::string>{};
  for (std::size_t k = 0; k < out.size() && k < blocks.size(); ++k) {
    const OutputBlockInfo& b = blocks[k];
    if (k) os << "\n";
    if (b.kind == OutputKind::Value && out[k].cols() == 1) {
      Table::vector(b.name, value_rows, out[k].col(0)).print(os);
    } else if (b.kind == OutputKind::Value) {
      Table::matrix(b.name, value_rows, out[k], value_columns).print(os);
    } else {
      const std::vector<std::string> columns = tangentLabels(b.wrt, model);
      const std::vector<std::string>& rows = b.kind == OutputKind::Hessian ? columns : derivative_rows;
      Table::matrix(b.name, rows, out[k], columns).print(os);
    }
  }
}

}  // namespace robodiff::cli
