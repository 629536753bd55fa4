// Fuzz target: the expression language of user functions. The text is parsed alone
// (core/language: lexer, parser, limits, the caret line of an error), then as the define
// of a user-function spec, and that spec is evaluated on double on two small robots (a
// fixed base and a floating base): name resolution, shapes of every operator, function
// and model primitive, indexing bounds, constant sizes, configurations. That is what
// GetFunction checks before any code is generated; the compile is not fuzzed.
//
// Expected failures are ExpressionError and SpecError (the expression or spec refused
// with a message); any other exception, a crash, a sanitizer report or a hang is a bug.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/language/parser.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace {

// A three-joint robot (revolute, prismatic, continuous) with a tool frame on a fixed joint.
constexpr const char* kRobot = R"(<robot name="fuzz_arm">
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.02" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="upper"><inertial><origin xyz="0 0 0.2"/><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.005" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="slider"><inertial><mass value="0.5"/><inertia ixx="0.002" iyy="0.002" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="wrist"><inertial><origin xyz="0.05 0 0"/><mass value="0.3"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tool"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="50" velocity="3"/></joint>
  <joint name="extend" type="prismatic"><parent link="upper"/><child link="slider"/><origin xyz="0 0 0.4"/><axis xyz="0 0 1"/><limit lower="0" upper="0.3" effort="100" velocity="1"/></joint>
  <joint name="twist" type="continuous"><parent link="slider"/><child link="wrist"/><axis xyz="1 0 0"/></joint>
  <joint name="tool_mount" type="fixed"><parent link="wrist"/><child link="tool"/><origin xyz="0.1 0 0"/></joint>
</robot>)";

struct Robot {
  robodiff::Model model;
};

const std::vector<Robot>& robots() {
  static const std::vector<Robot> all = {
      {robodiff::loadUrdfString(kRobot, robodiff::RootJoint::Fixed, "fuzz_arm")},
      {robodiff::loadUrdfString(kRobot, robodiff::RootJoint::FreeFlyer, "fuzz_arm")},
  };
  return all;
}

// The spec around the expression: the inputs, shapes and names an expression may use.
std::string specAround(const std::string& expression) {
  nlohmann::ordered_json spec = {
      {"name", "fuzz"},
      {"inputs", {{"q", "configuration"}, {"v", "nv"}, {"u", "nv"}, {"w", 3}, {"lam", "nv"},
                  {"k", {{"fixed", {40.0}}}}}},
      {"shapes", {{"hand", {{"frame", "tool"}, {"sphere", {{"center", {0, 0, 0.02}}, {"radius", 0.05}}}}},
                  {"arm", {{"frame", "upper"}, {"capsule", {{"a", {0, 0, 0}}, {"b", {0, 0, 0.4}}, {"radius", 0.04}}}}},
                  {"post", {{"frame", "world"}, {"capsule", {{"a", {0.5, 0, 0}}, {"b", {0.5, 0, 1}}, {"radius", 0.1}}}}}}},
      {"define", {{"e", expression}, {"half", "0.5 * v"}}},
      {"outputs", {{{"name", "y"}, {"kind", "value"}, {"of", "e"}}}},
  };
  // Invalid UTF-8 cannot travel inside a JSON string: replaced, as a client's encoder would.
  return spec.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

void evaluateOn(const robodiff::Model& model, const robodiff::FunctionSpec& spec) {
  Eigen::VectorXd q = robodiff::neutralConfiguration(model);
  q.head(model.nq - (model.root == robodiff::RootJoint::FreeFlyer ? 7 : 0)).setConstant(0.1);
  const Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(model.nv, -0.5, 0.5);
  const std::vector<Eigen::VectorXd> variable = {q, v, -v, Eigen::Vector3d(0.3, -0.2, 0.9),
                                                 Eigen::VectorXd::Ones(model.nv)};
  try {
    (void)robodiff::userReferenceValue(model, spec, 0, robodiff::completeInputs(spec, variable));
  } catch (const robodiff::SpecError&) {
    // a shape, name or bound refused with a message
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)robodiff::language::parseExpression(text);
  } catch (const robodiff::language::ExpressionError& e) {
    (void)robodiff::language::caretLine(text, e.column());
    return 0;
  }
  robodiff::FunctionSpec spec;
  try {
    spec = robodiff::parseFunctionSpec(specAround(text), "fuzz_spec");
  } catch (const robodiff::SpecError&) {
    return 0;
  }
  for (const Robot& robot : robots()) evaluateOn(robot.model, spec);
  return 0;
}
