// buildUserFunction: a user function traced on symbolic scalars with the tangents of
// its differentiated inputs carried along (user_evaluator.hpp), its first-order outputs
// read from those tangents, its Hessians by differentiating the traced value twice,
// then assembled into a compact graph of the runtime inputs.
#include "user_function_builder.hpp"

#include <chrono>
#include <optional>
#include <set>

#include "output_blocks.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "robodiff/symbolic/configuration.hpp"
#include "robodiff/symbolic/hessian.hpp"
#include "robodiff/symbolic/substitute.hpp"
#include "robodiff/symbolic/tracer.hpp"
#include "user_evaluator.hpp"

namespace robodiff::detail {

using symbolic::Graph;
using symbolic::NodeId;
using symbolic::Sym;

namespace {


bool firstOrder(UserOutputKind k) {
  return k == UserOutputKind::Jacobian || k == UserOutputKind::Gradient || k == UserOutputKind::Vjp;
}

// Where each differentiated input's tangent columns start, in input order.
struct TangentLayout {
  std::map<std::string, int> offset, width;
  int columns = 0;
  std::vector<int> columnsOf(const std::vector<std::string>& wrt) const {
    std::vector<int> out;
    for (const std::string& w : wrt)
      for (int k = 0; k < width.at(w); ++k) out.push_back(offset.at(w) + k);
    return out;
  }
};

struct Trace {
  Graph graph;
  symbolic::Tracer tracer{graph};
  std::map<std::string, std::vector<std::uint32_t>> hessian_indices;  // input -> indices to differentiate
  std::uint32_t runtime_inputs = 0;
};

// The inputs as values: runtime blocks (a configuration moved by its own dq block when a
// Hessian differentiates it and the model has a free-flyer), fixed numbers as constants,
// tangent seeds of identity for the differentiated inputs.
std::map<std::string, Value<Sym>> traceInputs(const Model& model, const UserFunction& f, const std::map<std::string, int>& sizes,
                                              const TangentLayout& layout, const std::set<std::string>& hessian_wrt, Trace& t) {
  std::map<std::string, VecX<Sym>> raw;
  for (const UserInput& in : f.inputs)
    if (in.kind != UserInput::Kind::Fixed) raw[in.name] = t.tracer.addInputs(in.name, sizes.at(in.name));
  t.runtime_inputs = t.graph.inputCount();
  std::map<std::string, Value<Sym>> values;
  for (const UserInput& in : f.inputs) {
    Value<Sym> v;
    if (in.kind == UserInput::Kind::Fixed) {
      v.m = Eigen::Map<const Eigen::VectorXd>(in.fixed.data(), static_cast<Eigen::Index>(in.fixed.size())).cast<Sym>();
      values[in.name] = v;
      continue;
    }
    VecX<Sym> x = raw[in.name];
    t.hessian_indices[in.name] = t.tracer.indices({in.name});
    if (in.kind == UserInput::Kind::Configuration && hessian_wrt.count(in.name) && hasFreeFlyer(model)) {
      const VecX<Sym> dq = t.tracer.addInputs("d_" + in.name, model.nv);
      t.hessian_indices[in.name] = t.tracer.indices({"d_" + in.name});
      x = symbolic::integrateSecondOrder(model, x, dq);
    }
    v.m = x;
    v.configuration = in.kind == UserInput::Kind::Configuration;
    if (layout.offset.count(in.name)) {
      v.has_tangent = true;
      const int rows = layout.width.at(in.name);
      v.d = MatX<Sym>::Zero(rows, layout.columns);
      for (int k = 0; k < rows; ++k) v.d(k, layout.offset.at(in.name) + k) = Sym(1.0);
    }
    values[in.name] = v;
  }
  return values;
}

std::vector<NodeId> nodesOf(Graph& g, const MatX<Sym>& m) {
  std::vector<NodeId> out;
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) out.push_back(m(r, c).nodeIn(g));
  return out;
}

// One output's nodes in the trace graph, and its rows x cols.
struct TracedOutput {
  std::vector<NodeId> nodes;
  int rows = 0, cols = 0;
  bool hessian = false;
};

TracedOutput traceOutput(const Model& model, const UserFunction& f, std::size_t k, const Value<Sym>& v, Evaluator<Sym>& ev,
                         const TangentLayout& layout, const std::map<std::string, Value<Sym>>& inputs, Trace& t) {
  const UserOutput& o = f.outputs[k];
  const std::string path = "outputs[" + std::to_string(k) + "]";
  TracedOutput out;
  Graph& g = t.graph;
  if (o.kind == UserOutputKind::Value) {
    const Value<Sym> c = ev.coordinates(v);
    out.rows = static_cast<int>(c.rows()), out.cols = static_cast<int>(c.cols());
    out.nodes = nodesOf(g, c.m);
    return out;
  }
  const std::vector<int> columns = o.kind == UserOutputKind::Hessian ? std::vector<int>() : layout.columnsOf(o.wrt);
  const int value_rows = static_cast<int>(v.configuration ? model.nv : v.size());
  // d value / d wrt, value_rows x |columns|.
  auto tangent = [&](int r, int c) { return v.has_tangent ? v.d(r, columns[c]) : Sym(0.0); };
  const int n = static_cast<int>(columns.size());
  if (o.kind == UserOutputKind::Jacobian) {
    out.rows = value_rows, out.cols = n;
    for (int r = 0; r < value_rows; ++r)
      for (int c = 0; c < n; ++c) out.nodes.push_back(tangent(r, c).nodeIn(g));
    return out;
  }
  if (o.kind == UserOutputKind::Gradient) {
    if (!v.isScalar()) throw SpecError(path + ": a gradient is of a scalar; '" + o.of + "' is " + shapeOf(v) + " (use a jacobian)");
    out.rows = n, out.cols = 1;
    for (int c = 0; c < n; ++c) out.nodes.push_back(tangent(0, c).nodeIn(g));
    return out;
  }
  if (o.kind == UserOutputKind::Vjp) {
    const Value<Sym>& lambda = inputs.at(o.lambda);
    if (lambda.size() != value_rows)
      throw SpecError(path + ".lambda: '" + o.lambda + "' has " + std::to_string(lambda.size()) + " entries, but '" + o.of +
                      "' has " + std::to_string(value_rows) + (v.configuration ? " tangent entries" : " entries"));
    out.rows = n, out.cols = 1;
    for (int c = 0; c < n; ++c) {
      Sym sum(0.0);
      for (int r = 0; r < value_rows; ++r)
        if (!isZero(tangent(r, c))) sum = sum + lambda.m(r, 0) * tangent(r, c);
      out.nodes.push_back(sum.nodeIn(g));
    }
    return out;
  }
  // Hessian: sum_i w_i d2 f_i / dx2 of the traced value, in the tangent space.
  if (v.configuration) throw SpecError(path + ": a Hessian is of a scalar or a weighted vector, not of a configuration");
  const std::vector<NodeId> value = nodesOf(g, v.m);
  std::vector<std::uint32_t> wrt;
  for (const std::string& w : o.wrt) wrt.insert(wrt.end(), t.hessian_indices.at(w).begin(), t.hessian_indices.at(w).end());
  symbolic::Hessian h;
  if (!o.weights_input.empty()) {
    const Value<Sym>& w = inputs.at(o.weights_input);
    if (w.size() != v.size())
      throw SpecError(path + ".weights: '" + o.weights_input + "' has " + std::to_string(w.size()) + " entries, but '" + o.of +
                      "' has " + std::to_string(v.size()));
    h = symbolic::weightedHessian(g, value, nodesOf(g, w.m), wrt);
  } else {
    const std::vector<double> weights = o.fixed_weights ? *o.fixed_weights : std::vector<double>{1.0};
    if (static_cast<Eigen::Index>(weights.size()) != v.size())
      throw SpecError(path + (o.fixed_weights ? ".weights: " + std::to_string(weights.size()) + " numbers, but '" : ": a Hessian without weights is of a scalar; '") +
                      o.of + "' is " + shapeOf(v));
    h = symbolic::weightedHessian(g, value, weights, wrt);
  }
  out.rows = out.cols = static_cast<int>(wrt.size());
  out.nodes = h.lower;
  out.hessian = true;
  return out;
}

struct Traced {
  std::unique_ptr<Trace> trace;
  std::vector<TracedOutput> outputs;
};

// Every shape's frame exists (before any expression refers to it).
void checkShapeFrames(const Model& model, const UserFunction& f) {
  for (const auto& [name, shape] : f.shapes) {
    try {
      resolveFrameName(model, shape.frame, 1);
    } catch (const EvalError& e) {
      throw SpecError("shapes." + name + ".frame: " + e.what());
    }
  }
}

Traced traceUserFunction(const Model& model, const FunctionSpec& spec, bool primitive_rules,
                         const FunctionBuilderOptions& options) {
  const std::size_t node_limit = options.node_limit;
  const UserFunction& f = *spec.user;
  checkShapeFrames(model, f);
  const std::map<std::string, int> sizes = inputSizes(model, f);
  TangentLayout layout;
  std::set<std::string> first_order, hessian_wrt;
  for (const UserOutput& o : f.outputs)
    for (const std::string& w : o.wrt) (firstOrder(o.kind) ? first_order : hessian_wrt).insert(w);
  for (const UserInput& in : f.inputs) {
    if (!first_order.count(in.name)) continue;
    layout.offset[in.name] = layout.columns;
    layout.width[in.name] = in.kind == UserInput::Kind::Configuration ? model.nv : sizes.at(in.name);
    layout.columns += layout.width[in.name];
  }
  Traced traced{std::make_unique<Trace>(), {}};
  Trace& t = *traced.trace;
  t.graph.setNodeLimit(node_limit);
  const std::map<std::string, Value<Sym>> inputs = traceInputs(model, f, sizes, layout, hessian_wrt, t);
  PrimitiveContext context{model, f, primitive_rules, node_limit, &t.graph};
  context.aba_by_factors = options.aba_value == AbaValueMethod::Factors;
  Evaluator<Sym> ev(context, inputs);
  for (std::size_t k = 0; k < f.outputs.size(); ++k)
    traced.outputs.push_back(traceOutput(model, f, k, ev.output(k), ev, layout, inputs, t));
  return traced;
}

// The traced outputs copied into a graph of the runtime inputs only (dq blocks at 0).
std::vector<std::vector<NodeId>> assemble(const Traced& traced, Graph& out) {
  const Trace& t = *traced.trace;
  std::vector<NodeId> input_map(t.graph.inputCount(), out.zero());
  for (std::uint32_t i = 0; i < t.runtime_inputs; ++i) input_map[i] = out.input(i);
  std::vector<std::vector<NodeId>> result;
  for (const TracedOutput& o : traced.outputs) result.push_back(symbolic::copyCone(t.graph, o.nodes, out, input_map));
  return result;
}

std::size_t operationsOf(const Traced& traced, std::size_t node_limit) {
  Graph g;
  g.setNodeLimit(node_limit);
  std::vector<NodeId> all;
  for (const std::vector<NodeId>& nodes : assemble(traced, g)) all.insert(all.end(), nodes.begin(), nodes.end());
  return symbolic::coneSize(g, all).operations;
}

}  // namespace

namespace {

bool exprCalls(const language::Expr& e, const std::string& name) {
  if (e.kind == language::ExprKind::Call && e.text == name) return true;
  auto calls = [&](const language::ExprPtr& p) { return p && exprCalls(*p, name); };
  for (const language::ExprPtr& a : e.args)
    if (calls(a)) return true;
  for (const std::vector<language::ExprPtr>& row : e.rows)
    for (const language::ExprPtr& a : row)
      if (calls(a)) return true;
  for (const language::IndexRange& r : e.ranges)
    if (calls(r.begin) || calls(r.end)) return true;
  return false;
}

}  // namespace

bool callsPrimitive(const UserFunction& f, const std::string& name) {
  for (const UserDefine& d : f.defines)
    if (d.expr && exprCalls(*d.expr, name)) return true;
  for (const UserOutput& o : f.outputs)
    if (o.of_expr && exprCalls(*o.of_expr, name)) return true;
  return false;
}

namespace {

BuiltFunction buildChecked(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options);

}  // namespace

// Errors found while building name the spec's source first, as the parser's do.
BuiltFunction buildUserFunction(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options) {
  const std::string source = spec.user->source.empty() ? "" : spec.user->source + ": ";
  try {
    return buildChecked(model, spec, options);
  } catch (const SpecTooLarge& e) {
    throw SpecTooLarge(source + e.what());
  } catch (const SpecError& e) {
    throw SpecError(source + e.what());
  }
}

namespace {

BuiltFunction buildChecked(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options) {
  const UserFunction& f = *spec.user;
  const auto start = std::chrono::steady_clock::now();
  Traced traced = traceUserFunction(model, spec, true, options);
  BuiltFunction built;
  built.timings.trace_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  built.trace_nodes = traced.trace->graph.size();
  built.graph = std::make_unique<Graph>();
  built.graph->setNodeLimit(options.node_limit);
  const auto t_assemble = std::chrono::steady_clock::now();
  const std::vector<std::vector<NodeId>> entries = assemble(traced, *built.graph);
  codegen::FunctionDefinition& def = built.definition;
  def.name = options.name.empty() ? f.name : options.name;
  const std::map<std::string, int> sizes = inputSizes(model, f);
  for (const UserInput& in : f.inputs)
    if (in.kind != UserInput::Kind::Fixed) def.inputs.push_back({in.name, static_cast<std::uint32_t>(sizes.at(in.name))});
  for (std::size_t k = 0; k < f.outputs.size(); ++k) {
    const UserOutput& o = f.outputs[k];
    const TracedOutput& t = traced.outputs[k];
    def.outputs.push_back(t.hessian ? hessianBlock(o.name, t.rows, entries[k], o.sparse, *built.graph)
                                    : matrixBlock(o.name, t.rows, t.cols, entries[k], o.sparse));
    BuiltOutput b;
    b.name = o.name;
    b.kind = spec.outputs[k].kind;
    b.wrt = o.wrt;
    b.layout = o.sparse ? Layout::Sparse : Layout::Dense;
    b.rows = t.rows, b.cols = t.cols;
    b.nnz = def.outputs.back().size();
    built.outputs.push_back(std::move(b));
  }
  def.validate(*built.graph);
  built.value_rows = built.outputs.front().rows;
  built.value_cols = built.outputs.front().cols;
  traced.trace.reset();
  built.timings.assemble_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_assemble).count();

  // The same function with every primitive's partials from differentiating its trace:
  // what the primitives' own rules save, in operations.
  built.method = "user function traced; first derivatives carried through the expression with the primitives' own rules";
  bool derivatives = false;
  for (const UserOutput& o : f.outputs) derivatives = derivatives || o.kind != UserOutputKind::Value;
  if (derivatives) {
    built.rule_operations = builtOperations(built);
    try {
      built.traced_operations = operationsOf(traceUserFunction(model, spec, false, options), options.node_limit);
      built.method += " (" + std::to_string(built.rule_operations) + " operations; " +
                      std::to_string(built.traced_operations) + " differentiating the primitives' traces)";
    } catch (const symbolic::GraphTooLarge&) {
      built.method += " (differentiating the primitives' traces exceeds the node limit)";
    }
  }
  if (options.aba_value == AbaValueMethod::Factors && callsPrimitive(f, "aba"))
    built.method += "; aba's value without tangents as M^-1 (tau - nle) by M's tree factors";
  bool hessian = false;
  for (const UserOutput& o : f.outputs) hessian = hessian || o.kind == UserOutputKind::Hessian;
  if (hessian) built.method += "; Hessians by differentiating the traced value twice";
  return built;
}

}  // namespace

}  // namespace robodiff::detail
