// `robodiff compute`: evaluate one dynamics function in double precision at one state.
#include <cstdio>
#include <iostream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "output_table.hpp"
#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "state_json.hpp"

namespace robodiff::cli {
namespace {

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

nlohmann::json placementJson(const SE3<double>& m) {
  return {{"translation", toJson(Eigen::VectorXd(m.translation))}, {"rotation", toJson(Eigen::MatrixXd(m.rotation))}};
}

// One label per velocity coordinate: the joint name, or name.vx ... name.wz.
std::vector<std::string> velocityLabels(const Model& model) {
  static const char* ff[] = {".vx", ".vy", ".vz", ".wx", ".wy", ".wz"};
  std::vector<std::string> labels;
  for (const Joint& j : model.joints)
    for (int k = 0; k < j.nv; ++k) labels.push_back(j.nv == 1 ? j.name : j.name + ff[k]);
  return labels;
}

struct Options {
  std::string urdf, function, frame, reference = "LOCAL_WORLD_ALIGNED", state, format = "json";
  bool floating_base = false;
  std::optional<std::uint64_t> random_state;
};

const std::vector<std::string> kFunctions = {"rnea", "aba",      "crba", "gravity",  "nle",
                                             "fk",   "jacobian", "com",  "regressor"};

void run(const Options& o) {
  Model model = loadUrdfFile(o.urdf, o.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed);
  State state;
  std::string source;
  if (o.random_state) {
    state = randomState(model, *o.random_state);
    source = "random state (seed " + std::to_string(*o.random_state) + ")";
  } else if (!o.state.empty()) {
    state = readStateFile(o.state);
    source = o.state;
  } else {
    throw std::invalid_argument("--state FILE or --random-state SEED is required");
  }
  const std::string& fn = o.function;
  // Check the inputs the function needs in q, v, a, tau order, so the first problem is named.
  static const std::map<std::string, std::vector<std::string>> inputs = {
      {"rnea", {"q", "v", "a"}}, {"aba", {"q", "v", "tau"}}, {"crba", {"q"}},  {"gravity", {"q"}},
      {"nle", {"q", "v"}},       {"fk", {"q"}},              {"jacobian", {"q"}}, {"com", {"q"}},
      {"regressor", {"q", "v", "a"}}};
  for (const std::string& key : inputs.at(fn)) require(state, model, key, fn, source);
  auto need = [&](const char* key) -> const Eigen::VectorXd& { return require(state, model, key, fn, source); };
  const ReferenceFrame reference = parseReferenceFrame(o.reference);
  std::optional<int> frame;
  if (!o.frame.empty()) {
    frame = model.findFrame(o.frame);
    if (!frame) throw std::invalid_argument("--frame: no frame named '" + o.frame + "' in " + o.urdf);
  }
  if (fn == "jacobian" && !frame) throw std::invalid_argument("--function jacobian needs --frame NAME");

  Data<double> data(model);
  nlohmann::json result;
  Table table;
  const std::vector<std::string> vlabels = velocityLabels(model);
  if (fn == "rnea" || fn == "aba" || fn == "gravity" || fn == "nle") {
    Eigen::VectorXd out;
    if (fn == "rnea") out = rnea(model, data, need("q"), need("v"), need("a"));
    if (fn == "aba") out = aba(model, data, need("q"), need("v"), need("tau"));
    if (fn == "gravity") out = computeGeneralizedGravity(model, data, need("q"));
    if (fn == "nle") out = nonLinearEffects(model, data, need("q"), need("v"));
    result = toJson(out);
    table = Table::vector(fn == "aba" ? "ddq" : "tau", vlabels, out);
  } else if (fn == "crba" || fn == "regressor") {
    Eigen::MatrixXd out = fn == "crba" ? Eigen::MatrixXd(crba(model, data, need("q")))
                                       : jointTorqueRegressor(model, data, need("q"), need("v"), need("a"));
    result = toJson(out);
    table = fn == "crba" ? Table::matrix("M(q)", vlabels, out, vlabels) : Table::matrix("Y(q, v, a)", vlabels, out);
  } else if (fn == "fk") {
    forwardKinematics(model, data, need("q"));
    updateFramePlacements(model, data);
    result = nlohmann::json::object();
    table = Table::placements();
    for (int f = 0; f < model.nframes(); ++f) {
      if (frame && f != *frame) continue;
      result[model.frames[f].name] = placementJson(data.oMf[f]);
      table.addPlacement(model.frames[f].name, data.oMf[f].translation, data.oMf[f].rotation);
    }
  } else if (fn == "jacobian") {
    Eigen::MatrixXd J = computeFrameJacobian(model, data, need("q"), *frame, reference);
    result = toJson(J);
    table = Table::matrix(std::string("J(") + o.frame + ", " + toString(reference) + ")",
                          {"vx", "vy", "vz", "wx", "wy", "wz"}, J, vlabels);
  } else if (fn == "com") {
    Eigen::Vector3d com = centerOfMass(model, data, need("q"));
    result = {{"com", toJson(Eigen::VectorXd(com))}, {"mass", data.mass}};
    table = Table::vector("centre of mass", {"x", "y", "z", "total mass"},
                          Eigen::Vector4d(com.x(), com.y(), com.z(), data.mass));
  }
  if (o.format == "table") {
    std::cout << fn << " of " << (model.name.empty() ? o.urdf : model.name) << " (nq = " << model.nq
              << ", nv = " << model.nv << ", " << source << ")\n";
    table.print(std::cout);
  } else {
    nlohmann::json out = {{"function", fn}, {"nq", model.nq}, {"nv", model.nv}, {"result", result}};
    if (fn == "jacobian") out["frame"] = o.frame, out["reference"] = toString(reference);
    std::cout << out.dump() << "\n";
  }
}

}  // namespace

void addComputeCommand(CLI::App& app) {
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("compute", "Evaluate a dynamics function in double precision at one state");
  cmd->add_option("--urdf", options->urdf, "Robot description (URDF file)")->required();
  cmd->add_flag("--floating-base", options->floating_base,
                "Add a free-flyer root joint (q = [x y z qx qy qz qw ...], v = [linear angular ...])");
  cmd->add_option("--function", options->function, "rnea|aba|crba|gravity|nle|fk|jacobian|com|regressor")
      ->required()
      ->check(CLI::IsMember(kFunctions));
  cmd->add_option("--frame", options->frame, "Frame name (jacobian; restricts fk to one frame)");
  cmd->add_option("--reference", options->reference, "Jacobian reference frame")
      ->check(CLI::IsMember({"LOCAL", "WORLD", "LOCAL_WORLD_ALIGNED"}));
  auto* state = cmd->add_option("--state", options->state, "State JSON {\"q\": [...], \"v\": [...], \"a\": [...], \"tau\": [...]}");
  auto* random = cmd->add_option("--random-state", options->random_state, "Use a random state drawn with this seed");
  state->excludes(random);
  cmd->add_option("--format", options->format, "json (default) or table")->check(CLI::IsMember({"json", "table"}));
  cmd->callback([options] { run(*options); });
}

}  // namespace robodiff::cli
