#include "robodiff/functions/function_spec.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "robodiff/language/bounded_text.hpp"
#include "build_options_json.hpp"
#include "user_function_canonical.hpp"
#include "user_function_json.hpp"
#include "user_function_parse.hpp"
#include "robodiff/language/json_problem.hpp"

namespace robodiff {

using nlohmann::json;

const std::vector<FunctionInfo>& modelFunctions() {
  static const std::vector<FunctionInfo> all = {
      {ModelFunction::Rnea, "rnea", {"q", "v", "a"}, false, "inverse dynamics tau = RNEA(q, v, a)"},
      {ModelFunction::Aba, "aba", {"q", "v", "tau"}, false, "forward dynamics ddq = ABA(q, v, tau)"},
      {ModelFunction::Crba, "crba", {"q"}, false, "joint-space mass matrix M(q), nv x nv"},
      {ModelFunction::Gravity, "gravity", {"q"}, false, "generalised gravity g(q)"},
      {ModelFunction::Nle, "nle", {"q", "v"}, false, "nonlinear effects C(q, v) v + g(q)"},
      {ModelFunction::Fk, "fk", {"q"}, true, "placement of a frame in the world, 3 x 4 [R | p]"},
      {ModelFunction::FrameJacobian, "frame_jacobian", {"q"}, true, "6 x nv Jacobian of a frame"},
      {ModelFunction::Com, "com", {"q"}, false, "centre of mass in the world"},
      {ModelFunction::Regressor, "regressor", {"q", "v", "a"}, false, "joint-torque regressor, nv x 10 njoints"},
      {ModelFunction::Minv, "minv", {"q"}, false, "inverse of the mass matrix, nv x nv"},
  };
  return all;
}

const FunctionInfo& functionInfo(ModelFunction f) {
  for (const FunctionInfo& info : modelFunctions())
    if (info.function == f) return info;
  throw std::logic_error("functionInfo: unknown function");
}

const char* toString(ModelFunction f) { return functionInfo(f).name; }

const char* toString(OutputKind k) {
  switch (k) {
    case OutputKind::Value: return "value";
    case OutputKind::Jacobian: return "jacobian";
    case OutputKind::Hessian: return "hessian";
  }
  return "?";
}

const InputSpec& FunctionSpec::input(const std::string& name) const {
  for (const InputSpec& i : inputs)
    if (i.name == name) return i;
  throw std::invalid_argument(functionName() + " has no input '" + name + "'");
}

std::string FunctionSpec::functionName() const { return user ? user->name : std::string(toString(function)); }

std::vector<std::string> FunctionSpec::inputNames() const {
  if (!user) return functionInfo(function).inputs;
  std::vector<std::string> names;
  for (const InputSpec& i : inputs) names.push_back(i.name);
  return names;
}

namespace {

// A value quoted in a message: its JSON, cut to a short prefix when long.
std::string shown(const json& value) { return language::boundedText(value.dump()); }

// Keys whose string values are names (frames, functions, kinds, ...), not expressions.
bool holdsName(const std::string& key) {
  static const std::set<std::string> keys = {"frame", "name", "function", "kind", "layout", "reference",
                                             "optimization", "wrt"};
  return keys.count(key) != 0;
}

// Refuses (SpecTooLarge) any key, and any name-holding string value, longer than
// kMaxSpecNameBytes, before anything else reads them. Iterative: no recursion on depth.
void checkNameLengths(const nlohmann::ordered_json& root, const std::string& source) {
  struct Item {
    const nlohmann::ordered_json* value;
    std::string path;
    bool is_name;  // a string here is a name
  };
  std::vector<Item> pending = {{&root, "", false}};
  while (!pending.empty()) {
    const Item item = std::move(pending.back());
    pending.pop_back();
    const nlohmann::ordered_json& value = *item.value;
    if (value.is_string() && item.is_name && value.get_ref<const std::string&>().size() > kMaxSpecNameBytes)
      throw SpecTooLarge(source + ": " + item.path + ": a name of " +
                         std::to_string(value.get_ref<const std::string&>().size()) + " bytes, past the limit of " +
                         std::to_string(kMaxSpecNameBytes) + " bytes for names in a spec");
    if (value.is_object()) {
      for (const auto& [key, child] : value.items()) {
        if (key.size() > kMaxSpecNameBytes)
          throw SpecTooLarge(source + ": " + (item.path.empty() ? "" : item.path + ": ") + "a key of " +
                             std::to_string(key.size()) + " bytes, past the limit of " +
                             std::to_string(kMaxSpecNameBytes) + " bytes for names in a spec");
        pending.push_back({&child, item.path.empty() ? key : item.path + "." + key, holdsName(key)});
      }
    } else if (value.is_array()) {
      for (std::size_t i = 0; i < value.size(); ++i)
        pending.push_back({&value[i], item.path + "[" + std::to_string(i) + "]", item.is_name});
    }
  }
}

class Parser {
 public:
  explicit Parser(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw SpecError(source_ + ": " + (path.empty() ? "" : path + ": ") + what);
  }

  void onlyKeys(const json& object, const std::string& path, std::initializer_list<const char*> allowed) const {
    for (const auto& [key, _] : object.items()) {
      bool known = key == "description" || key == "$comment" || key == "$schema";
      for (const char* a : allowed) known = known || key == a;
      if (!known) {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(path.empty() ? key : path + "." + key, "unknown field (expected one of: " + list + ")");
      }
    }
  }

  // "layout": dense (the default) or sparse.
  Layout layoutOf(const json& output, const std::string& path) const {
    if (!output.contains("layout")) return Layout::Dense;
    const std::string layout = string(output["layout"], path + ".layout");
    if (layout == "sparse") return Layout::Sparse;
    if (layout != "dense") fail(path + ".layout", language::quote(layout) + " is neither dense nor sparse");
    return Layout::Dense;
  }

  std::string string(const json& value, const std::string& path) const {
    if (!value.is_string()) fail(path, shown(value) + " is not a string");
    return value.get<std::string>();
  }

  std::vector<double> numbers(const json& value, const std::string& path) const {
    if (!value.is_array()) fail(path, shown(value) + " is not an array of numbers");
    std::vector<double> out;
    for (size_t i = 0; i < value.size(); ++i) {
      const std::string at = path + "[" + std::to_string(i) + "]";
      if (!value[i].is_number()) fail(at, shown(value[i]) + " is not a number");
      double x = value[i].get<double>();
      if (!std::isfinite(x)) fail(at, "not a finite number");
      out.push_back(x);
    }
    return out;
  }

  std::vector<std::string> wrtList(const json& value, const std::string& path, const FunctionSpec& spec) const {
    const FunctionInfo& info = functionInfo(spec.function);
    if (!value.is_array() || value.empty()) fail(path, "must be a non-empty array of input names");
    std::vector<std::string> out;
    for (size_t i = 0; i < value.size(); ++i) {
      const std::string at = path + "[" + std::to_string(i) + "]";
      std::string name = string(value[i], at);
      bool known = false;
      for (const std::string& input : info.inputs) known = known || input == name;
      if (!known) {
        std::string list;
        for (const std::string& input : info.inputs) list += (list.empty() ? "" : ", ") + input;
        fail(at, language::quote(name) + " is not an input of " + info.name + " (its inputs: " + list + ")");
      }
      if (spec.input(name).fixed)
        fail(at, language::quote(name) + " is fixed; only variable inputs can be differentiated against");
      for (const std::string& seen : out)
        if (seen == name) fail(at, language::quote(name) + " is listed twice");
      out.push_back(name);
    }
    return out;
  }

  FunctionSpec parse(const std::string& text) {
    nlohmann::ordered_json ordered;
    try {
      ordered = nlohmann::ordered_json::parse(text);
    } catch (const nlohmann::ordered_json::exception& e) {  // parse_error, and out_of_range for 1e400
      fail("", "not valid JSON: " + language::jsonProblem(e.what()));
    }
    if (!ordered.is_object()) fail("", "a spec is a JSON object");
    checkNameLengths(ordered, source_);
    if (detail::isUserFunctionJson(ordered)) return parseUser(ordered);
    const json root = json::parse(text);
    onlyKeys(root, "", {"function", "inputs", "outputs", "frame", "reference", "build"});
    FunctionSpec spec;
    parseBuild(root, spec);
    const FunctionInfo& info = parseFunction(root, spec);
    parseInputs(root, info, spec);
    parseOutputs(root, spec);
    parseFrame(root, info, spec);
    return spec;
  }

  // "function": the model function, with its inputs all variable.
  const FunctionInfo& parseFunction(const json& root, FunctionSpec& spec) {
    if (!root.contains("function")) fail("function", "missing (one of: " + functionList() + ")");
    const std::string name = string(root["function"], "function");
    const FunctionInfo* info = nullptr;
    for (const FunctionInfo& f : modelFunctions())
      if (name == f.name) info = &f;
    if (!info) fail("function", language::quote(name) + " is not a model function (one of: " + functionList() + ")");
    spec.function = info->function;
    for (const std::string& input : info->inputs) spec.inputs.push_back({input, std::nullopt});
    return *info;
  }

  // "inputs": each "variable" or {"fixed": [numbers]}.
  void parseInputs(const json& root, const FunctionInfo& info, FunctionSpec& spec) {
    if (!root.contains("inputs")) return;
    const json& inputs = root["inputs"];
    if (!inputs.is_object()) fail("inputs", "must be an object {\"q\": \"variable\", \"v\": {\"fixed\": [...]}, ...}");
    for (const auto& [key, value] : inputs.items()) {
      const std::string path = "inputs." + key;
      InputSpec* target = nullptr;
      for (InputSpec& i : spec.inputs)
        if (i.name == key) target = &i;
      if (!target) fail(path, language::quote(key) + " is not an input of " + info.name);
      if (value.is_string() && value.get<std::string>() == "variable") continue;
      if (value.is_object() && value.size() == 1 && value.contains("fixed")) {
        target->fixed = numbers(value["fixed"], path + ".fixed");
        continue;
      }
      fail(path, shown(value) + " is neither \"variable\" nor {\"fixed\": [numbers]}");
    }
  }

  // "outputs": a non-empty array of values, Jacobians and Hessians.
  void parseOutputs(const json& root, FunctionSpec& spec) {
    if (!root.contains("outputs")) fail("outputs", "missing: list at least one output, e.g. [{\"kind\": \"value\"}]");
    const json& outputs = root["outputs"];
    if (!outputs.is_array() || outputs.empty()) fail("outputs", "must be a non-empty array");
    for (size_t i = 0; i < outputs.size(); ++i) spec.outputs.push_back(output(outputs[i], "outputs[" + std::to_string(i) + "]", spec));
  }

  OutputSpec output(const json& o, const std::string& path, const FunctionSpec& spec) {
    if (!o.is_object()) fail(path, shown(o) + " is not an object {\"kind\": ...}");
    if (!o.contains("kind")) fail(path + ".kind", "missing (value, jacobian or hessian)");
    const std::string kind = string(o["kind"], path + ".kind");
    OutputSpec out;
    if (kind == "value") {
      onlyKeys(o, path, {"kind"});
      return out;
    }
    if (kind != "jacobian" && kind != "hessian")
      fail(path + ".kind", language::quote(kind) + " is not an output kind (value, jacobian or hessian)");
    const bool hessian = kind == "hessian";
    if (hessian) onlyKeys(o, path, {"kind", "wrt", "weights", "layout"});
    else onlyKeys(o, path, {"kind", "wrt", "layout"});
    out.kind = hessian ? OutputKind::Hessian : OutputKind::Jacobian;
    if (!o.contains("wrt")) fail(path + ".wrt", "missing: the inputs to differentiate against");
    out.wrt = wrtList(o["wrt"], path + ".wrt", spec);
    out.layout = layoutOf(o, path);
    if (hessian && o.contains("weights") && !(o["weights"].is_string() && o["weights"] == "input"))
      out.fixed_weights = numbers(o["weights"], path + ".weights");
    return out;
  }

  // "frame" where the function needs one (and nowhere else); "reference" for a frame
  // Jacobian.
  void parseFrame(const json& root, const FunctionInfo& info, FunctionSpec& spec) {
    if (info.needs_frame) {
      if (!root.contains("frame")) fail("frame", std::string("missing: ") + info.name + " needs a frame name");
      spec.frame = string(root["frame"], "frame");
      if (spec.frame.empty()) fail("frame", "empty frame name");
    } else if (root.contains("frame")) {
      fail("frame", shown(root["frame"]) + " given, but " + info.name + " takes no frame");
    }
    if (!root.contains("reference")) return;
    if (spec.function != ModelFunction::FrameJacobian)
      fail("reference", std::string("only frame_jacobian takes a reference frame, not ") + info.name);
    const std::string ref = string(root["reference"], "reference");
    try {
      spec.reference = parseReferenceFrame(ref);
    } catch (const std::invalid_argument& e) {
      fail("reference", e.what());
    }
  }

  // A user function: inputs, defines, outputs (user_function_parse.cpp), build options.
  FunctionSpec parseUser(const nlohmann::ordered_json& ordered) {
    FunctionSpec spec;
    spec.user = std::make_shared<const UserFunction>(detail::parseUserFunction(ordered, source_));
    detail::fillSpecView(spec);
    parseBuild(json::parse(ordered.dump()), spec);
    return spec;
  }

  // "target": "native" | "x86-64" (march_native true / false) | an x86-64 level, which
  // turns march_native off; a march_native that says otherwise is refused.
  void parseTarget(const json& b, BuildOptions& build) const {
    const std::string target = string(b["target"], "build.target");
    const bool level = std::find_if(std::begin(kTargetLevels), std::end(kTargetLevels),
                                    [&](const char* l) { return target == l; }) != std::end(kTargetLevels);
    if (!level && target != "native" && target != "x86-64") {
      std::string valid = "native, x86-64";
      for (const char* l : kTargetLevels) valid += std::string(", ") + l;
      fail("build.target", language::quote(target) + " is not one of " + valid);
    }
    const bool native = target == "native";
    if (b.contains("march_native") && build.march_native != native)
      fail("build.march_native", std::string(build.march_native ? "true" : "false") + " contradicts target " +
                                     language::quote(target));
    build.march_native = native;
    if (level) build.target = target;
  }

  void parseBuild(const json& root, FunctionSpec& spec) const {
    if (root.contains("build")) {
      const json& b = root["build"];
      if (!b.is_object()) fail("build", "must be an object");
      onlyKeys(b, "build", {"optimization", "march_native", "fast_math", "target", "batch"});
      if (b.contains("optimization")) {
        spec.build.optimization = string(b["optimization"], "build.optimization");
        const std::set<std::string> levels = {"O0", "O1", "O2", "O3"};
        if (!levels.count(spec.build.optimization))
          fail("build.optimization", language::quote(spec.build.optimization) + " is not one of O0, O1, O2, O3");
      }
      for (auto [flag, field] : {std::pair{"march_native", &BuildOptions::march_native},
                                 std::pair{"fast_math", &BuildOptions::fast_math}, std::pair{"batch", &BuildOptions::batch}}) {
        if (!b.contains(flag)) continue;
        if (!b[flag].is_boolean()) fail(std::string("build.") + flag, shown(b[flag]) + " is not true or false");
        spec.build.*field = b[flag].get<bool>();
      }
      if (b.contains("target")) parseTarget(b, spec.build);
    }
  }

 private:
  static std::string functionList() {
    std::string list;
    for (const FunctionInfo& f : modelFunctions()) list += (list.empty() ? "" : ", ") + std::string(f.name);
    return list;
  }
  std::string source_;
};

}  // namespace

FunctionSpec parseFunctionSpec(const std::string& json_text, const std::string& source) {
  return Parser(source).parse(json_text);
}

FunctionSpec loadFunctionSpec(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SpecError(path + ": cannot open spec file");
  std::ostringstream text;
  text << in.rdbuf();
  return parseFunctionSpec(text.str(), path);
}

std::string normalizedSpecJson(const FunctionSpec& spec) {
  if (spec.user) return detail::canonicalUserFunctionJson(spec);
  json j;
  j["function"] = toString(spec.function);
  json inputs = json::object();
  for (const InputSpec& i : spec.inputs) {
    if (i.fixed) inputs[i.name] = {{"fixed", *i.fixed}};
    else inputs[i.name] = "variable";
  }
  j["inputs"] = inputs;
  json outputs = json::array();
  for (const OutputSpec& o : spec.outputs) {
    json out = {{"kind", toString(o.kind)}};
    if (o.kind != OutputKind::Value) out["wrt"] = o.wrt;
    if (o.kind != OutputKind::Value) out["layout"] = o.layout == Layout::Sparse ? "sparse" : "dense";
    if (o.kind == OutputKind::Hessian) out["weights"] = o.fixed_weights ? json(*o.fixed_weights) : json("input");
    outputs.push_back(out);
  }
  j["outputs"] = outputs;
  if (functionInfo(spec.function).needs_frame) j["frame"] = spec.frame;
  if (spec.function == ModelFunction::FrameJacobian) j["reference"] = toString(spec.reference);
  j["build"] = detail::buildOptionsJson<json>(spec.build);
  return j.dump();
}

std::string specJson(const FunctionSpec& spec) {
  return spec.user ? detail::userFunctionSpecJson(spec) : normalizedSpecJson(spec);
}

}  // namespace robodiff
