#include "user_function_json.hpp"

#include <nlohmann/json.hpp>

#include "build_options_json.hpp"

namespace robodiff::detail {

namespace {

using nlohmann::ordered_json;

ordered_json point(const Eigen::Vector3d& p) { return ordered_json::array({p.x(), p.y(), p.z()}); }

// Inputs in their order (the runtime blocks' order), sizes as written ("nv", "2 * nv").
ordered_json inputsJson(const UserFunction& f) {
  ordered_json inputs = ordered_json::object();
  for (const UserInput& in : f.inputs) {
    switch (in.kind) {
      case UserInput::Kind::Configuration: inputs[in.name] = "configuration"; break;
      case UserInput::Kind::Vector: inputs[in.name] = in.size; break;
      case UserInput::Kind::Fixed: inputs[in.name] = {{"fixed", in.fixed}}; break;
    }
  }
  return inputs;
}

ordered_json shapesJson(const UserFunction& f) {
  ordered_json shapes = ordered_json::object();
  for (const auto& [name, s] : f.shapes) {
    ordered_json geometry;
    if (s.kind == UserShape::Kind::Sphere) {
      geometry = {{"center", point(s.a)}, {"radius", s.radius}};
      shapes[name] = {{"frame", s.frame}, {"sphere", geometry}};
    } else {
      geometry = {{"a", point(s.a)}, {"b", point(s.b)}, {"radius", s.radius}};
      shapes[name] = {{"frame", s.frame}, {"capsule", geometry}};
    }
  }
  return shapes;
}

ordered_json outputJson(const UserOutput& o) {
  ordered_json out = {{"name", o.name}, {"kind", toString(o.kind)}, {"of", o.of}};
  if (o.kind == UserOutputKind::Value) return out;
  out["wrt"] = o.wrt;
  if (o.sparse) out["layout"] = "sparse";
  if (!o.weights_input.empty()) out["weights"] = o.weights_input;
  if (o.fixed_weights) out["weights"] = *o.fixed_weights;
  if (!o.lambda.empty()) out["lambda"] = o.lambda;
  return out;
}

}  // namespace

std::string userFunctionSpecJson(const FunctionSpec& spec) {
  const UserFunction& f = *spec.user;
  ordered_json j;
  j["name"] = f.name;
  j["inputs"] = inputsJson(f);
  if (!f.shapes.empty()) j["shapes"] = shapesJson(f);
  ordered_json defines = ordered_json::object();
  for (const UserDefine& d : f.defines) defines[d.name] = d.text;
  if (!f.defines.empty()) j["define"] = defines;
  ordered_json outputs = ordered_json::array();
  for (const UserOutput& o : f.outputs) outputs.push_back(outputJson(o));
  j["outputs"] = outputs;
  j["build"] = buildOptionsJson<ordered_json>(spec.build);
  return j.dump();
}

}  // namespace robodiff::detail
