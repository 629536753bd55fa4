#include "user_function_parse.hpp"

#include <cmath>
#include <algorithm>
#include <regex>
#include <set>

#include "robodiff/language/parser.hpp"
#include "robodiff/language/bounded_text.hpp"
#include "robodiff/language/suggest.hpp"

namespace robodiff::detail {

using nlohmann::ordered_json;

namespace {

const std::set<std::string> kReservedNames = {"nq", "nv", "pi"};

bool isIdentifier(const std::string& s) {
  static const std::regex id("[A-Za-z_][A-Za-z0-9_]*");
  return s.size() <= 128 && std::regex_match(s, id);
}

// A short quote of a value for messages (a 10 MB string is not repeated whole).
std::string quoted(const ordered_json& value) { return language::boundedText(value.dump()); }

class UserParser {
 public:
  UserParser(std::string source, const UserFunctionLimits& limits) : source_(std::move(source)), limits_(limits) {}

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw SpecError(source_ + ": " + path + ": " + what);
  }
  [[noreturn]] void tooLarge(const std::string& path, const std::string& what) const {
    throw SpecTooLarge(source_ + ": " + path + ": " + what);
  }

  UserFunction parse(const ordered_json& root) {
    onlyKeys(root, "", {"name", "inputs", "define", "outputs", "shapes", "build", "description", "$comment", "$schema"});
    UserFunction f;
    if (root.contains("name")) {
      f.name = string(root["name"], "name");
      if (!isIdentifier(f.name)) fail("name", quoted(root["name"]) + " is not a C identifier (letters, digits, _)");
    }
    parseInputs(root, f);
    parseDefines(root, f);
    parseShapes(root, f);
    parseOutputs(root, f);
    return f;
  }

 private:
  void onlyKeys(const ordered_json& object, const std::string& path, std::initializer_list<const char*> allowed) const {
    std::vector<std::string> names(allowed.begin(), allowed.end());
    for (const auto& [key, _] : object.items()) {
      if (std::find(names.begin(), names.end(), key) != names.end()) continue;
      fail(path.empty() ? key : path + "." + key, "unknown field" + language::didYouMean(key, names));
    }
  }

  std::string string(const ordered_json& value, const std::string& path) const {
    if (!value.is_string()) fail(path, quoted(value) + " is not a string");
    return value.get<std::string>();
  }

  std::vector<double> numbers(const ordered_json& value, const std::string& path) const {
    if (!value.is_array()) fail(path, quoted(value) + " is not an array of numbers");
    if (value.size() > limits_.max_input_size) tooLarge(path, std::to_string(value.size()) + " numbers, more than the limit");
    std::vector<double> out;
    for (std::size_t i = 0; i < value.size(); ++i) {
      const std::string at = path + "[" + std::to_string(i) + "]";
      if (!value[i].is_number()) fail(at, quoted(value[i]) + " is not a number");
      const double x = value[i].get<double>();
      if (!std::isfinite(x)) fail(at, "not a finite number");
      out.push_back(x);
    }
    return out;
  }

  Eigen::Vector3d point(const ordered_json& value, const std::string& path) const {
    const std::vector<double> p = numbers(value, path);
    if (p.size() != 3) fail(path, "a point has 3 coordinates, not " + std::to_string(p.size()));
    return {p[0], p[1], p[2]};
  }

  // One expression, its syntax errors and limits reported at `path`.
  language::ExprPtr expression(const std::string& text, const std::string& path) {
    language::ParseLimits limits;
    limits.max_length = limits_.max_expression_length;
    limits.max_depth = limits_.max_depth;
    limits.max_nodes = limits_.max_nodes;
    try {
      language::ExprPtr e = language::parseExpression(text, limits);
      if (treeDepth(*e) > kMaxTreeDepth)
        tooLarge(path, "the expression nests deeper than " + std::to_string(kMaxTreeDepth) + " operations (a chain of + or * counts each)");
      nodes_ += countNodes(*e);
      if (nodes_ > limits_.max_nodes)
        tooLarge(path, "the spec's expressions have more than " + std::to_string(limits_.max_nodes) + " terms");
      return e;
    } catch (const language::ExpressionTooLarge& e) {
      tooLarge(path, e.what());
    } catch (const language::ExpressionError& e) {
      fail(path, std::string(e.what()) + language::caretLine(text, e.column()));
    }
  }

  // Long chains such as a + b + c + ... parse into deep trees; the evaluator walks them
  // recursively, so their depth is bounded here (checked without recursion).
  static constexpr std::size_t kMaxTreeDepth = 400;
  static std::size_t treeDepth(const language::Expr& root) {
    std::size_t deepest = 0;
    std::vector<std::pair<const language::Expr*, std::size_t>> stack{{&root, 1}};
    while (!stack.empty()) {
      const auto [e, depth] = stack.back();
      stack.pop_back();
      deepest = std::max(deepest, depth);
      if (deepest > kMaxTreeDepth) return deepest;
      for (const auto& a : e->args) stack.emplace_back(a.get(), depth + 1);
      for (const auto& row : e->rows)
        for (const auto& a : row) stack.emplace_back(a.get(), depth + 1);
      for (const auto& r : e->ranges) {
        if (r.begin) stack.emplace_back(r.begin.get(), depth + 1);
        if (r.end) stack.emplace_back(r.end.get(), depth + 1);
      }
    }
    return deepest;
  }

  static std::size_t countNodes(const language::Expr& e) {
    std::size_t n = 1;
    for (const auto& a : e.args) n += countNodes(*a);
    for (const auto& row : e.rows)
      for (const auto& a : row) n += countNodes(*a);
    for (const auto& r : e.ranges) n += (r.begin ? countNodes(*r.begin) : 0) + (r.end ? countNodes(*r.end) : 0);
    return n;
  }

  void newName(const std::string& name, const std::string& path, const std::set<std::string>& taken) const {
    if (!isIdentifier(name)) fail(path, language::quote(name) + " is not a name (letters, digits, _)");
    if (kReservedNames.count(name)) fail(path, "'" + name + "' is reserved (nq, nv and pi are constants)");
    if (taken.count(name)) fail(path, "'" + name + "' is already an input or a define");
  }

  void parseInputs(const ordered_json& root, UserFunction& f) {
    if (!root.contains("inputs")) fail("inputs", "missing: e.g. {\"q\": \"configuration\", \"v\": \"nv\"}");
    const ordered_json& inputs = root["inputs"];
    if (!inputs.is_object() || inputs.empty()) fail("inputs", "must be a non-empty object of input names");
    if (inputs.size() > limits_.max_inputs) tooLarge("inputs", std::to_string(inputs.size()) + " inputs, more than the limit");
    for (const auto& [key, value] : inputs.items()) {
      const std::string path = "inputs." + key;
      newName(key, path, names_);
      names_.insert(key);
      UserInput in;
      in.name = key;
      if (value.is_string() && value.get<std::string>() == "configuration") {
        in.kind = UserInput::Kind::Configuration;
      } else if (value.is_number_integer() || value.is_number_unsigned()) {
        if (value.get<long long>() < 1) fail(path, "a size must be at least 1");
        if (value.get<long long>() > static_cast<long long>(limits_.max_input_size)) tooLarge(path, "size past the limit");
        in.size = std::to_string(value.get<long long>());
        in.size_expr = expression(in.size, path);
      } else if (value.is_string()) {
        in.size = value.get<std::string>();
        in.size_expr = expression(in.size, path);
      } else if (value.is_object() && value.size() == 1 && value.contains("fixed")) {
        in.kind = UserInput::Kind::Fixed;
        in.fixed = numbers(value["fixed"], path + ".fixed");
        if (in.fixed.empty()) fail(path + ".fixed", "must hold at least one number");
      } else {
        fail(path, quoted(value) + " is not \"configuration\", a size (3, \"nv\", \"2 * nv\") or {\"fixed\": [numbers]}");
      }
      f.inputs.push_back(std::move(in));
    }
  }

  void parseDefines(const ordered_json& root, UserFunction& f) {
    if (!root.contains("define")) return;
    const ordered_json& defines = root["define"];
    if (!defines.is_object()) fail("define", "must be an object {\"name\": \"expression\", ...}");
    if (defines.size() > limits_.max_defines) tooLarge("define", std::to_string(defines.size()) + " defines, more than the limit");
    for (const auto& [key, value] : defines.items()) {
      const std::string path = "define." + key;
      newName(key, path, names_);
      names_.insert(key);
      const std::string text = string(value, path);
      f.define_index[key] = f.defines.size();
      f.defines.push_back({key, text, expression(text, path)});
    }
  }

  void parseShapes(const ordered_json& root, UserFunction& f) {
    if (!root.contains("shapes")) return;
    const ordered_json& shapes = root["shapes"];
    if (!shapes.is_object()) fail("shapes", "must be an object of named shapes");
    for (const auto& [key, value] : shapes.items()) {
      const std::string path = "shapes." + key;
      if (!isIdentifier(key)) fail(path, language::quote(key) + " is not a name");
      if (!value.is_object()) fail(path, "must be {\"frame\": ..., \"sphere\"|\"capsule\": {...}}");
      onlyKeys(value, path, {"frame", "sphere", "capsule"});
      UserShape s;
      if (!value.contains("frame")) fail(path + ".frame", "missing: the frame the shape is attached to (or \"world\")");
      s.frame = string(value["frame"], path + ".frame");
      const bool sphere = value.contains("sphere"), capsule = value.contains("capsule");
      if (sphere == capsule) fail(path, "give exactly one of \"sphere\" and \"capsule\"");
      const std::string geometry_path = path + (sphere ? ".sphere" : ".capsule");
      const ordered_json& g = value[sphere ? "sphere" : "capsule"];
      if (!g.is_object()) fail(geometry_path, "must be an object");
      if (sphere) {
        onlyKeys(g, geometry_path, {"center", "radius"});
        s.kind = UserShape::Kind::Sphere;
        s.a = s.b = g.contains("center") ? point(g["center"], geometry_path + ".center") : Eigen::Vector3d::Zero();
      } else {
        onlyKeys(g, geometry_path, {"a", "b", "radius"});
        s.kind = UserShape::Kind::Capsule;
        if (!g.contains("a") || !g.contains("b")) fail(geometry_path, "a capsule needs its segment's ends \"a\" and \"b\"");
        s.a = point(g["a"], geometry_path + ".a");
        s.b = point(g["b"], geometry_path + ".b");
      }
      if (!g.contains("radius") || !g["radius"].is_number()) fail(geometry_path + ".radius", "missing or not a number");
      s.radius = g["radius"].get<double>();
      if (!(s.radius >= 0) || !std::isfinite(s.radius)) fail(geometry_path + ".radius", "must be a finite number >= 0");
      f.shapes[key] = s;
    }
  }

  std::vector<std::string> wrtList(const ordered_json& value, const std::string& path, const UserFunction& f) const {
    if (!value.is_array() || value.empty()) fail(path, "must be a non-empty array of input names");
    std::vector<std::string> variable, out;
    for (const UserInput& in : f.inputs)
      if (in.kind != UserInput::Kind::Fixed) variable.push_back(in.name);
    for (std::size_t i = 0; i < value.size(); ++i) {
      const std::string at = path + "[" + std::to_string(i) + "]";
      const std::string name = string(value[i], at);
      const UserInput* in = f.input(name);
      if (!in) fail(at, language::quote(name) + " is not an input" + language::didYouMean(name, variable));
      if (in->kind == UserInput::Kind::Fixed) fail(at, "'" + name + "' is fixed; only variable inputs can be differentiated against");
      if (std::find(out.begin(), out.end(), name) != out.end()) fail(at, "'" + name + "' is listed twice");
      out.push_back(name);
    }
    return out;
  }

  std::string variableInput(const ordered_json& value, const std::string& path, const UserFunction& f) const {
    const std::string name = string(value, path);
    const UserInput* in = f.input(name);
    std::vector<std::string> names;
    for (const UserInput& i : f.inputs) names.push_back(i.name);
    if (!in) fail(path, language::quote(name) + " is not an input" + language::didYouMean(name, names));
    if (in->kind != UserInput::Kind::Vector) fail(path, "'" + name + "' must be a variable vector input (a size)");
    return name;
  }

  void parseOutputs(const ordered_json& root, UserFunction& f) {
    if (!root.contains("outputs")) fail("outputs", "missing: e.g. [{\"name\": \"y\", \"kind\": \"value\", \"of\": \"y\"}]");
    const ordered_json& outputs = root["outputs"];
    if (!outputs.is_array() || outputs.empty()) fail("outputs", "must be a non-empty array");
    if (outputs.size() > limits_.max_outputs) tooLarge("outputs", std::to_string(outputs.size()) + " outputs, more than the limit");
    std::set<std::string> output_names;
    for (std::size_t i = 0; i < outputs.size(); ++i) {
      const std::string path = "outputs[" + std::to_string(i) + "]";
      const ordered_json& o = outputs[i];
      if (!o.is_object()) fail(path, quoted(o) + " is not an object {\"name\": ..., \"kind\": ..., \"of\": ...}");
      f.outputs.push_back(parseOutput(o, path, f));
      const std::string& name = f.outputs.back().name;
      if (!output_names.insert(name).second) fail(path + ".name", "'" + name + "' names two outputs");
    }
  }

  UserOutput parseOutput(const ordered_json& o, const std::string& path, const UserFunction& f) {
    UserOutput out;
    for (const char* required : {"name", "kind", "of"})
      if (!o.contains(required)) fail(path + "." + required, "missing");
    out.name = string(o["name"], path + ".name");
    if (!isIdentifier(out.name)) fail(path + ".name", language::quote(out.name) + " is not a name (letters, digits, _)");
    const std::string kind = string(o["kind"], path + ".kind");
    static const std::vector<std::string> kinds = {"value", "jacobian", "gradient", "hessian", "vjp"};
    const auto k = std::find(kinds.begin(), kinds.end(), kind);
    if (k == kinds.end()) fail(path + ".kind", language::quote(kind) + " is not an output kind (value, jacobian, gradient, hessian, vjp)" + language::didYouMean(kind, kinds));
    out.kind = static_cast<UserOutputKind>(k - kinds.begin());
    out.of = string(o["of"], path + ".of");
    out.of_expr = expression(out.of, path + ".of");
    switch (out.kind) {
      case UserOutputKind::Value: onlyKeys(o, path, {"name", "kind", "of", "description"}); break;
      case UserOutputKind::Jacobian: onlyKeys(o, path, {"name", "kind", "of", "wrt", "layout", "description"}); break;
      case UserOutputKind::Gradient: onlyKeys(o, path, {"name", "kind", "of", "wrt", "description"}); break;
      case UserOutputKind::Hessian: onlyKeys(o, path, {"name", "kind", "of", "wrt", "layout", "weights", "description"}); break;
      case UserOutputKind::Vjp: onlyKeys(o, path, {"name", "kind", "of", "wrt", "lambda", "description"}); break;
    }
    if (out.kind == UserOutputKind::Value) return out;
    if (!o.contains("wrt")) fail(path + ".wrt", "missing: the inputs to differentiate against");
    out.wrt = wrtList(o["wrt"], path + ".wrt", f);
    if (o.contains("layout")) {
      const std::string layout = string(o["layout"], path + ".layout");
      if (layout != "dense" && layout != "sparse") fail(path + ".layout", language::quote(layout) + " is neither dense nor sparse");
      out.sparse = layout == "sparse";
    }
    if (o.contains("weights")) {
      if (o["weights"].is_string()) out.weights_input = variableInput(o["weights"], path + ".weights", f);
      else out.fixed_weights = numbers(o["weights"], path + ".weights");
    }
    if (out.kind == UserOutputKind::Vjp) {
      if (!o.contains("lambda")) fail(path + ".lambda", "missing: the input holding lambda (a vector the size of the value)");
      out.lambda = variableInput(o["lambda"], path + ".lambda", f);
    }
    return out;
  }

  std::string source_;
  UserFunctionLimits limits_;
  std::set<std::string> names_;  // inputs and defines
  std::size_t nodes_ = 0;
};

}  // namespace

}  // namespace robodiff::detail

namespace robodiff {

const char* toString(UserOutputKind kind) {
  switch (kind) {
    case UserOutputKind::Value: return "value";
    case UserOutputKind::Jacobian: return "jacobian";
    case UserOutputKind::Gradient: return "gradient";
    case UserOutputKind::Hessian: return "hessian";
    case UserOutputKind::Vjp: return "vjp";
  }
  return "?";
}

const UserInput* UserFunction::input(const std::string& name) const {
  for (const UserInput& i : inputs)
    if (i.name == name) return &i;
  return nullptr;
}

const UserDefine* UserFunction::define(const std::string& name) const {
  const auto it = define_index.find(name);
  return it == define_index.end() ? nullptr : &defines[it->second];
}

}  // namespace robodiff

namespace robodiff::detail {

bool isUserFunctionJson(const ordered_json& root) {
  if (!root.is_object() || root.contains("function")) return false;
  if (root.contains("define")) return true;
  if (root.contains("outputs") && root["outputs"].is_array())
    for (const ordered_json& o : root["outputs"])
      if (o.is_object() && o.contains("of")) return true;
  return false;
}

UserFunction parseUserFunction(const ordered_json& root, const std::string& source, const UserFunctionLimits& limits) {
  UserFunction f = UserParser(source, limits).parse(root);
  f.source = source;
  return f;
}

void fillSpecView(FunctionSpec& spec) {
  spec.inputs.clear();
  spec.outputs.clear();
  for (const UserInput& in : spec.user->inputs) {
    InputSpec i{in.name, std::nullopt};
    if (in.kind == UserInput::Kind::Fixed) i.fixed = in.fixed;
    spec.inputs.push_back(std::move(i));
  }
  for (const UserOutput& o : spec.user->outputs) {
    OutputSpec out;
    out.wrt = o.wrt;
    out.layout = o.sparse ? Layout::Sparse : Layout::Dense;
    if (o.kind == UserOutputKind::Jacobian) out.kind = OutputKind::Jacobian;
    if (o.kind == UserOutputKind::Hessian) {
      out.kind = OutputKind::Hessian;
      out.fixed_weights = o.fixed_weights ? *o.fixed_weights : std::vector<double>{1.0};
    }
    spec.outputs.push_back(std::move(out));
  }
}

}  // namespace robodiff::detail
