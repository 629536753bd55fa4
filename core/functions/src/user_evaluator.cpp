#include "user_evaluator.hpp"

#include <algorithm>
#include <cmath>

#include "robodiff/language/parser.hpp"
#include "robodiff/language/bounded_text.hpp"
#include "robodiff/language/suggest.hpp"
#include "robodiff/symbolic/configuration.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/substitute.hpp"
#include "robodiff/symbolic/tracer.hpp"
#include "user_math.hpp"
#include "user_primitive_rules.hpp"

namespace robodiff::detail {

using language::Expr;
using language::ExprKind;
using symbolic::Sym;

int constantInteger(const Expr& e, const Model& model, const std::string& what) {
  switch (e.kind) {
    case ExprKind::Number:
      if (e.number != std::floor(e.number) || std::abs(e.number) > 1e8)
        throw EvalError(e.column, what + " must be an integer, not " + std::to_string(e.number));
      return static_cast<int>(e.number);
    case ExprKind::Name:
      if (e.text == "nq") return model.nq;
      if (e.text == "nv") return model.nv;
      break;
    case ExprKind::Unary:
      return e.text == "-" ? -constantInteger(*e.args[0], model, what) : constantInteger(*e.args[0], model, what);
    case ExprKind::Binary: {
      const long long a = constantInteger(*e.args[0], model, what), b = constantInteger(*e.args[1], model, what);
      const long long r = e.text == "+" ? a + b : e.text == "-" ? a - b : e.text == "*" ? a * b : (1LL << 40);
      if (r == (1LL << 40)) break;
      if (std::llabs(r) > 100000000) throw EvalError(e.column, what + " is too large");
      return static_cast<int>(r);
    }
    default: break;
  }
  throw EvalError(e.column, what + " must be a constant integer (numbers, nq, nv, + - *)");
}

std::map<std::string, int> inputSizes(const Model& model, const UserFunction& f) {
  std::map<std::string, int> sizes;
  for (const UserInput& in : f.inputs) {
    if (in.kind == UserInput::Kind::Configuration) sizes[in.name] = model.nq;
    else if (in.kind == UserInput::Kind::Fixed) sizes[in.name] = static_cast<int>(in.fixed.size());
    else {
      try {
        sizes[in.name] = constantInteger(*in.size_expr, model, "the size");
      } catch (const EvalError& e) {
        throw SpecError("inputs." + in.name + ": '" + in.size + "': " + e.what());
      }
      if (sizes[in.name] > 100000)
        throw SpecTooLarge("inputs." + in.name + ": size " + std::to_string(sizes[in.name]) + " is past the limit of 100000");
      if (sizes[in.name] < 1)
        throw SpecError("inputs." + in.name + ": size " + std::to_string(sizes[in.name]) + " is not between 1 and 100000");
    }
  }
  return sizes;
}

template <class S>
Evaluator<S>::Evaluator(const PrimitiveContext& context, std::map<std::string, Value<S>> inputs)
    : context_(context), inputs_(std::move(inputs)) {}

template <class S> Value<S> Evaluator<S>::located(const Expr& e, const std::string& path, const std::string& text) {
  try {
    return eval(e);
  } catch (const EvalTooLarge& error) {
    throw SpecTooLarge(path + ": column " + std::to_string(error.column()) + ": " + error.what() + language::caretLine(text, error.column()));
  } catch (const EvalError& error) {
    throw SpecError(path + ": column " + std::to_string(error.column()) + ": " + error.what() + language::caretLine(text, error.column()));
  }
}

template <class S> Value<S> Evaluator<S>::output(std::size_t k) {
  const UserOutput& o = context_.function.outputs.at(k);
  return located(*o.of_expr, "outputs[" + std::to_string(k) + "].of", o.of);
}

template <class S> Value<S> Evaluator<S>::coordinates(const Value<S>& v) {
  if (!v.configuration) return v;
  Value<S> out = v;
  out.configuration = false;
  if constexpr (kTracesTangents<S>) {
    if (!v.has_tangent || !hasFreeFlyer(context_.model)) return out;
    // d coordinates / d tangent at q: integrateSecondOrder differentiated at dq = 0.
    const Model& model = context_.model;
    symbolic::Graph scratch;
    symbolic::Tracer tracer(scratch);
    const VecX<Sym> p = tracer.addInputs("p", model.nq), dq = tracer.addInputs("dq", model.nv);
    const std::vector<symbolic::NodeId> moved = tracer.outputs(symbolic::integrateSecondOrder(model, p, dq));
    const symbolic::Jacobian J = symbolic::jacobian(scratch, moved, tracer.indices({"dq"}));
    std::vector<symbolic::NodeId> input_map;
    for (int i = 0; i < model.nq; ++i) input_map.push_back(v.m(i, 0).nodeIn(*context_.graph));
    for (int i = 0; i < model.nv; ++i) input_map.push_back(context_.graph->zero());
    const std::vector<symbolic::NodeId> copied = symbolic::copyCone(scratch, J.entries, *context_.graph, input_map);
    MatX<Sym> C(model.nq, model.nv);
    for (int r = 0; r < model.nq; ++r)
      for (int c = 0; c < model.nv; ++c) C(r, c) = Sym(*context_.graph, copied[static_cast<std::size_t>(r) * model.nv + c]);
    out.d = sparseProduct(C, v.d);
  }
  return out;
}

template <class S> void Evaluator<S>::charge(std::uint64_t entries, int column) {
  work_ += entries;
  if (work_ > kMaxEvaluatedEntries)
    throw EvalTooLarge(column, "the expressions compute more than " + std::to_string(kMaxEvaluatedEntries) +
                                   " entries (values and derivatives, in all), the limit on a user function's work");
}

template <class S> Value<S> Evaluator<S>::eval(const Expr& e) {
  Value<S> v = evalNode(e);
  charge(static_cast<std::uint64_t>(v.m.size()) + static_cast<std::uint64_t>(v.d.size()), e.column);
  return v;
}

template <class S> Value<S> Evaluator<S>::evalNode(const Expr& e) {
  switch (e.kind) {
    case ExprKind::Number: {
      Value<S> v;
      v.m = MatX<S>::Constant(1, 1, S(e.number));
      return v;
    }
    case ExprKind::String:
      throw EvalError(e.column, "a string (" + language::quote(e.text) + ") only names a frame, a shape or a reference frame, as a primitive's argument");
    case ExprKind::Name: return name(e);
    case ExprKind::Call: return call(e);
    case ExprKind::Unary: {
      const Value<S> x = evalCoordinates(e.args[0]);
      return e.text == "-" ? scaled(x, -1.0) : x;
    }
    case ExprKind::Binary: return binary(e);
    case ExprKind::Matrix: return matrix(e);
    case ExprKind::Index: return index(e);
    case ExprKind::Transpose: return transposed(evalCoordinates(e.args[0]));
  }
  throw EvalError(e.column, "unknown expression");
}

template <class S> Value<S> Evaluator<S>::name(const Expr& e) {
  if (const auto it = inputs_.find(e.text); it != inputs_.end()) return it->second;
  if (const auto it = defines_.find(e.text); it != defines_.end()) return it->second;
  if (const UserDefine* d = context_.function.define(e.text)) {
    if (!evaluating_.insert(e.text).second)
      throw EvalError(e.column, "define '" + e.text + "' depends on itself");
    const Value<S> v = located(*d->expr, "define." + d->name, d->text);
    evaluating_.erase(e.text);
    return defines_[e.text] = v;
  }
  Value<S> constant;
  if (e.text == "nq" || e.text == "nv" || e.text == "pi") {
    const double x = e.text == "nq" ? context_.model.nq : e.text == "nv" ? context_.model.nv : M_PI;
    constant.m = MatX<S>::Constant(1, 1, S(x));
    return constant;
  }
  std::vector<std::string> names = {"nq", "nv", "pi"};
  for (const auto& [n, _] : inputs_) names.push_back(n);
  for (const UserDefine& d : context_.function.defines) names.push_back(d.name);
  throw EvalError(e.column, "unknown name " + language::quote(e.text) + language::didYouMean(e.text, names));
}

template <class S> Value<S> Evaluator<S>::call(const Expr& e) {
  const int column = e.column;
  if (e.text == "eye" || e.text == "zeros") {
    if (e.args.empty() || e.args.size() > (e.text == "eye" ? 1u : 2u))
      throw EvalError(column, e.text + "() takes " + (e.text == "eye" ? "one size" : "one or two sizes"));
    const int rows = constantInteger(*e.args[0], context_.model, e.text + "()'s size");
    const int cols = e.args.size() > 1 ? constantInteger(*e.args[1], context_.model, "zeros()'s size") : e.text == "eye" ? rows : 1;
    if (rows < 1 || cols < 1 || rows > 10000 || cols > 10000) throw EvalError(column, e.text + "(): sizes between 1 and 10000");
    if (work_ + static_cast<std::uint64_t>(rows) * static_cast<std::uint64_t>(cols) > kMaxEvaluatedEntries)
      charge(static_cast<std::uint64_t>(rows) * static_cast<std::uint64_t>(cols), column);  // throws, before allocating
    Value<S> v;
    v.m = e.text == "eye" ? MatX<S>(MatX<S>::Identity(rows, cols)) : MatX<S>(MatX<S>::Zero(rows, cols));
    return v;
  }
  const std::vector<std::string>& math = mathFunctionNames();
  if (!findPrimitive(e.text) && std::find(math.begin(), math.end(), e.text) == math.end()) {
    std::vector<std::string> names = math;
    for (const PrimitiveSignature& s : primitiveSignatures()) names.push_back(s.name);
    throw EvalError(column, "unknown function " + language::quote(e.text) + language::didYouMean(e.text, names));
  }
  if (const PrimitiveSignature* signature = findPrimitive(e.text)) {
    std::vector<PrimitiveArg<S>> args;
    for (const language::ExprPtr& a : e.args) {
      PrimitiveArg<S> arg;
      arg.column = a->column;
      if (a->kind == ExprKind::String) arg.is_string = true, arg.text = a->text;
      else arg.value = eval(*a);
      args.push_back(std::move(arg));
    }
    return callPrimitive(context_, *signature, args, column);
  }
  std::vector<Value<S>> args;
  for (const language::ExprPtr& a : e.args) args.push_back(evalCoordinates(a));
  Value<S> out;
  callMath(e.text, args, column, out);
  return out;
}

template <class S> Value<S> Evaluator<S>::binary(const Expr& e) {
  const Value<S> a = evalCoordinates(e.args[0]), b = evalCoordinates(e.args[1]);
  const std::string& op = e.text;
  const std::string what = "'" + op + "'";
  using P = std::pair<S, S>;
  if (op == "@") {  // its multiply-adds (with the tangents') are charged before they run
    const auto tangents = static_cast<std::uint64_t>(std::max(a.d.cols(), b.d.cols()));
    if (a.cols() == b.rows())
      charge(static_cast<std::uint64_t>(a.rows()) * static_cast<std::uint64_t>(a.cols()) *
                 static_cast<std::uint64_t>(b.cols()) * (1 + tangents), e.column);
    return matrixProduct(a, b, e.column);
  }
  if (op == "+" || op == "-") {
    const double sign = op == "+" ? 1.0 : -1.0;
    return zipEntries<S>(a, b, what.c_str(), e.column, [sign](const S& x, const S& y) { return S(sign > 0 ? x + y : x - y); },
                         [sign](const S&, const S&, const S&) { return P(S(1.0), S(sign)); });
  }
  if (op == "*")
    return zipEntries<S>(a, b, what.c_str(), e.column, [](const S& x, const S& y) { return S(x * y); },
                         [](const S& x, const S& y, const S&) { return P(y, x); });
  if (op == "/")
    return zipEntries<S>(a, b, what.c_str(), e.column, [](const S& x, const S& y) { return S(x / y); },
                         [](const S&, const S& y, const S& r) { return P(S(S(1.0) / y), S(-r / y)); });
  // '^': x^2 as x * x (what the generated code computes fastest); pow otherwise.
  if (b.isScalar() && !b.has_tangent && e.args[1]->kind == ExprKind::Number && e.args[1]->number == 2.0)
    return zipEntries<S>(a, a, what.c_str(), e.column, [](const S& x, const S&) { return S(x * x); },
                         [](const S& x, const S&, const S&) { return P(x, x); });
  return binaryMath<S>("pow", a, b, e.column);
}

template <class S> Value<S> Evaluator<S>::matrix(const Expr& e) {
  std::vector<Value<S>> rows;
  for (const auto& row : e.rows) {
    std::vector<Value<S>> parts;
    for (const language::ExprPtr& element : row) parts.push_back(evalCoordinates(element));
    rows.push_back(parts.size() == 1 ? parts.front() : concatenate(parts, true, e.column));
  }
  return rows.size() == 1 ? rows.front() : concatenate(rows, false, e.column);
}

template <class S> Value<S> Evaluator<S>::index(const Expr& e) {
  const Value<S> x = evalCoordinates(e.args[0]);
  // Bounds of one range along an axis of length n: [begin, end).
  auto bounds = [&](const language::IndexRange& r, Eigen::Index n) {
    const Model& m = context_.model;
    int begin = r.begin ? constantInteger(*r.begin, m, "an index") : 0;
    int end = r.is_slice ? (r.end ? constantInteger(*r.end, m, "an index") : static_cast<int>(n)) : begin + 1;
    if (begin < 0 || end > n || begin >= end)
      throw EvalError(e.column, "index " + (r.is_slice ? std::to_string(begin) + ":" + std::to_string(end) : std::to_string(begin)) +
                                    " is outside 0.." + std::to_string(n) + " of a " + shapeOf(x) + " value (0-based, end excluded)");
    return std::pair<int, int>(begin, end);
  };
  std::pair<int, int> rows{0, static_cast<int>(x.rows())}, cols{0, static_cast<int>(x.cols())};
  if (e.ranges.size() == 2) {
    rows = bounds(e.ranges[0], x.rows());
    cols = bounds(e.ranges[1], x.cols());
  } else if (x.cols() == 1) {
    rows = bounds(e.ranges[0], x.rows());
  } else if (x.rows() == 1) {
    cols = bounds(e.ranges[0], x.cols());
  } else {
    throw EvalError(e.column, "a " + shapeOf(x) + " matrix takes two indices, M[i, j] or M[i:j, k:l]");
  }
  std::vector<Eigen::Index> source;
  for (int r = rows.first; r < rows.second; ++r)
    for (int c = cols.first; c < cols.second; ++c) source.push_back(x.at(r, c));
  return gather(x, rows.second - rows.first, cols.second - cols.first, source);
}

template class Evaluator<double>;
template class Evaluator<Sym>;

}  // namespace robodiff::detail
