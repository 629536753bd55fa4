#include "user_function_canonical.hpp"

#include <cstdio>
#include <map>
#include <set>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "build_options_json.hpp"

namespace robodiff::detail {

namespace {

using language::Expr;
using language::ExprKind;

std::string exactNumber(double x) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

// Numbers the distinct terms of a user function's expressions in the order they are
// first completed (depth first, arguments left to right), defines inlined.
class TermTable {
 public:
  explicit TermTable(const UserFunction& f) : f_(f) {}

  // The term number of an expression.
  std::size_t term(const Expr& e) {
    if (const auto it = memo_.find(&e); it != memo_.end()) return it->second;
    // A define's name is its expression's term: inline or named, one term.
    if (const UserDefine* d = e.kind == ExprKind::Name ? f_.define(e.text) : nullptr) {
      if (!inlining_.insert(e.text).second) return add("cycle");  // reported by the builder
      const std::size_t id = term(*d->expr);
      inlining_.erase(e.text);
      return memo_[&e] = id;
    }
    const std::size_t id = add(describe(e));
    memo_[&e] = id;
    return id;
  }

  const std::vector<std::string>& terms() const { return terms_; }

 private:
  std::size_t add(const std::string& text) {
    const auto [it, inserted] = ids_.try_emplace(text, terms_.size());
    if (inserted) terms_.push_back(text);
    return it->second;
  }

  std::string ref(const language::ExprPtr& e) { return e ? "#" + std::to_string(term(*e)) : "_"; }

  std::string describe(const Expr& e) {
    switch (e.kind) {
      case ExprKind::Number: return "num " + exactNumber(e.number);
      case ExprKind::String: return "str " + stringArgument(e.text);
      case ExprKind::Name: return "name " + e.text;
      case ExprKind::Call: return "call " + e.text + list(e.args);
      case ExprKind::Unary: return "unary " + e.text + list(e.args);
      case ExprKind::Binary: return "binary " + e.text + list(e.args);
      case ExprKind::Transpose: return "transpose" + list(e.args);
      case ExprKind::Matrix: {
        std::string text = "matrix";
        for (const auto& row : e.rows) text += " row" + list(row);
        return text;
      }
      case ExprKind::Index: {
        std::string text = "index" + list(e.args);
        for (const auto& r : e.ranges) text += std::string(r.is_slice ? " slice " : " at ") + ref(r.begin) + ":" + ref(r.end);
        return text;
      }
    }
    return "?";
  }

  std::string list(const std::vector<language::ExprPtr>& args) {
    std::string text = "(";
    for (std::size_t k = 0; k < args.size(); ++k) text += (k ? "," : "") + ref(args[k]);
    return text + ")";
  }

  // A shape's name is replaced by what it is: renaming a shape changes nothing.
  std::string stringArgument(const std::string& text) {
    const auto it = f_.shapes.find(text);
    if (it == f_.shapes.end()) return text;
    const UserShape& s = it->second;
    std::string out = std::string(s.kind == UserShape::Kind::Sphere ? "sphere" : "capsule") + "@" + s.frame;
    for (int k = 0; k < 3; ++k) out += " " + exactNumber(s.a[k]);
    for (int k = 0; k < 3; ++k) out += " " + exactNumber(s.b[k]);
    return out + " r " + exactNumber(s.radius);
  }

  const UserFunction& f_;
  std::unordered_map<const Expr*, std::size_t> memo_;
  std::unordered_map<std::string, std::size_t> ids_;
  std::vector<std::string> terms_;
  std::set<std::string> inlining_;
};

}  // namespace

std::string canonicalUserFunctionJson(const FunctionSpec& spec) {
  const UserFunction& f = *spec.user;
  using nlohmann::json;
  json inputs = json::array();
  for (const UserInput& in : f.inputs) {
    if (in.kind == UserInput::Kind::Configuration) inputs.push_back({in.name, "configuration"});
    else if (in.kind == UserInput::Kind::Fixed) inputs.push_back({in.name, {{"fixed", in.fixed}}});
    else inputs.push_back({in.name, in.size});
  }
  TermTable table(f);
  json outputs = json::array();
  for (const UserOutput& o : f.outputs) {
    json out = {{"name", o.name}, {"kind", toString(o.kind)}, {"of", table.term(*o.of_expr)}};
    if (o.kind != UserOutputKind::Value) out["wrt"] = o.wrt;
    if (o.sparse) out["layout"] = "sparse";
    if (!o.weights_input.empty()) out["weights"] = o.weights_input;
    if (o.fixed_weights) out["weights"] = *o.fixed_weights;
    if (!o.lambda.empty()) out["lambda"] = o.lambda;
    outputs.push_back(out);
  }
  // Input size expressions in canonical form too ("nv" and " nv " are one size).
  for (json& in : inputs)
    if (in[1].is_string() && in[1] != "configuration")
      for (const UserInput& u : f.inputs)
        if (u.name == in[0] && u.size_expr) in[1] = "#" + std::to_string(table.term(*u.size_expr));
  json j;
  j["user_function"] = f.name;
  j["inputs"] = inputs;
  j["terms"] = table.terms();
  j["outputs"] = outputs;
  j["build"] = buildOptionsJson<json>(spec.build);
  return j.dump();
}

}  // namespace robodiff::detail
