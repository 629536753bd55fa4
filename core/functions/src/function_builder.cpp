#include "robodiff/functions/function_builder.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <set>

#include "robodiff/dynamics/minv.hpp"
#include "robodiff/dynamics/rnea_derivatives.hpp"
#include "robodiff/functions/model_function.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "robodiff/symbolic/configuration.hpp"
#include "robodiff/symbolic/hessian.hpp"
#include "robodiff/symbolic/substitute.hpp"
#include "robodiff/symbolic/sym.hpp"
#include "robodiff/symbolic/tracer.hpp"
#include "output_blocks.hpp"
#include "user_function_builder.hpp"
#include "user_primitive_rules.hpp"

namespace robodiff {

using symbolic::Graph;
using symbolic::NodeId;
using symbolic::Sym;
using detail::hasFreeFlyer;

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}


// Output block names: value, jacobian, hessian; with several of a kind, named by what
// they differentiate against (jacobian_q_v), and made unique.
std::vector<std::string> outputNames(const FunctionSpec& spec) {
  std::map<OutputKind, int> count;
  for (const OutputSpec& o : spec.outputs) ++count[o.kind];
  std::vector<std::string> names;
  std::set<std::string> used;
  for (const OutputSpec& o : spec.outputs) {
    std::string name = toString(o.kind);
    if (count[o.kind] > 1)
      for (const std::string& w : o.wrt) name += "_" + w;
    if (count[o.kind] > 1 && o.layout == Layout::Sparse) name += "_sparse";
    std::string unique = name;
    for (int k = 2; used.count(unique); ++k) unique = name + "_" + std::to_string(k);
    used.insert(unique);
    names.push_back(unique);
  }
  return names;
}

// The n x n row-major blocks named by `wrt`, side by side: an n x (n |wrt|) row-major
// Jacobian.
std::vector<NodeId> sideBySide(const std::map<std::string, std::vector<NodeId>>& blocks,
                               const std::vector<std::string>& wrt, int n) {
  const std::size_t cols = static_cast<std::size_t>(n) * wrt.size();
  std::vector<NodeId> out(static_cast<std::size_t>(n) * cols);
  for (std::size_t r = 0; r < static_cast<std::size_t>(n); ++r)
    for (std::size_t b = 0; b < wrt.size(); ++b)
      for (std::size_t c = 0; c < static_cast<std::size_t>(n); ++c)
        out[r * cols + b * n + c] = blocks.at(wrt[b])[r * n + c];
  return out;
}

// -M^-1 B for an n x n row-major block B, by solves with M's tree factors (LD as
// factorizeMassMatrix leaves them, row-major; user_primitive_rules.hpp). Against the
// dense product M^-1 B (which the builder used before): free-flying Talos ABA + Jacobian
// 181,520 -> 153,680 operations (36.5-37.1 -> 33.1 µs); fixed Talos 63,615 -> 59,419.
std::vector<NodeId> solveWithMassFactors(Graph& graph, const Model& model, const std::vector<NodeId>& LD,
                                         const std::vector<NodeId>& B, int n) {
  MatX<Sym> factors(n, n), rhs(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      factors(r, c) = Sym(graph, LD[static_cast<std::size_t>(r) * n + c]);
      rhs(r, c) = -Sym(graph, B[static_cast<std::size_t>(r) * n + c]);
    }
  const MatX<Sym> X = detail::solveWithMassFactors(model, factors, rhs);
  std::vector<NodeId> out;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) out.push_back(X(r, c).nodeIn(graph));
  return out;
}

// The working trace: the model function on symbolic inputs, in a graph that may also
// hold helper inputs (the tangent displacement dq, ABA's a*) that the assembled
// function does not have.
struct Trace {
  Graph graph;
  symbolic::Tracer tracer{graph};
  std::vector<VecX<Sym>> inputs;  // every function input (fixed ones as constants), q moved by dq
  std::vector<std::string> variable_names;
  bool tangent = false;           // q-derivatives are taken w.r.t. the block "dq"
  std::vector<NodeId> value;      // row-major
  std::vector<NodeId> weights;    // the "weights" block, when a Hessian takes them as input
};

}  // namespace

namespace {

// One build with the methods `options` names (never RneaJacobianMethod::Cheaper).
BuiltFunction buildOneWay(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options) {
  const FunctionInfo& info = functionInfo(spec.function);
  const int frame = resolveFrame(model, spec);
  const auto [rows, cols] = valueShape(model, spec.function);
  const int value_size = rows * cols;

  // Checks the parser could not make without the model.
  for (const InputSpec& in : spec.inputs)
    if (in.fixed && static_cast<int>(in.fixed->size()) != inputSize(model, in.name))
      throw SpecError("inputs." + in.name + ".fixed: " + std::to_string(in.fixed->size()) + " numbers, but " +
                      (model.name.empty() ? "the model" : model.name) + " has " + (in.name == "q" ? "nq" : "nv") +
                      " = " + std::to_string(inputSize(model, in.name)));
  bool weights_input = false;
  std::set<std::string> q_derivatives_needed;
  for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
    const OutputSpec& o = spec.outputs[k];
    for (const std::string& w : o.wrt) q_derivatives_needed.insert(w);
    if (o.kind != OutputKind::Hessian) continue;
    if (o.fixed_weights && static_cast<int>(o.fixed_weights->size()) != value_size)
      throw SpecError("outputs[" + std::to_string(k) + "].weights: " + std::to_string(o.fixed_weights->size()) +
                      " numbers, but the value of " + info.name + " has " + std::to_string(value_size) + " entries");
    if (!o.fixed_weights) weights_input = true;
  }

  auto trace = std::make_unique<Trace>();
  trace->graph.setNodeLimit(options.node_limit);
  Graph& g = trace->graph;
  symbolic::Tracer& tracer = trace->tracer;
  const auto t_trace = std::chrono::steady_clock::now();

  // Function inputs in order; fixed ones are constants.
  for (const std::string& name : info.inputs) {
    const InputSpec& in = spec.input(name);
    if (in.fixed) {
      trace->inputs.push_back(Eigen::Map<const Eigen::VectorXd>(in.fixed->data(), in.fixed->size()).cast<Sym>());
    } else {
      trace->inputs.push_back(tracer.addInputs(name, inputSize(model, name)));
      trace->variable_names.push_back(name);
    }
  }
  if (weights_input) {
    const VecX<Sym> w = tracer.addInputs("weights", value_size);
    trace->weights = tracer.outputs(w);
  }
  const int runtime_inputs = static_cast<int>(g.inputCount());
  // The tangent displacement: only a free-flyer's q-derivatives differ from partials.
  const bool q_variable = !spec.input("q").fixed;
  trace->tangent = q_variable && hasFreeFlyer(model) && q_derivatives_needed.count("q");
  const VecX<Sym> q_plain = trace->inputs[0];  // analytic derivatives are tangent already
  if (trace->tangent) {
    const VecX<Sym> dq = tracer.addInputs("dq", model.nv);
    trace->inputs[0] = symbolic::integrateSecondOrder(model, trace->inputs[0], dq);
  }
  Data<Sym> data(model);
  trace->value = tracer.outputs(modelFunctionValue(model, data, spec, frame, trace->inputs));
  BuiltFunction built;
  built.timings.trace_seconds = secondsSince(t_trace);
  built.value_rows = rows;
  built.value_cols = cols;

  // The tangent columns of named inputs (q -> dq when moving on the manifold).
  auto wrtIndices = [&](const std::vector<std::string>& names) {
    std::vector<std::string> blocks;
    for (const std::string& n : names) blocks.push_back(n == "q" && trace->tangent ? "dq" : n);
    return tracer.indices(blocks);
  };

  bool any_jacobian = false;
  for (const OutputSpec& o : spec.outputs) any_jacobian = any_jacobian || o.kind == OutputKind::Jacobian;
  const bool rnea_analytic = options.rnea_jacobian == RneaJacobianMethod::Analytic;
  const bool aba_partials_analytic = options.aba_rnea_partials == RneaJacobianMethod::Analytic;
  // ABA's Jacobian from RNEA's partials at a = ddq.
  const bool aba_analytic =
      spec.function == ModelFunction::Aba && options.aba_jacobian == AbaJacobianMethod::Analytic && any_jacobian;

  const auto t_diff = std::chrono::steady_clock::now();
  // Per output, the nodes of the trace graph (for the analytic ABA Jacobian: the
  // pieces, assembled in the final graph below).
  std::vector<std::vector<NodeId>> trace_outputs(spec.outputs.size());
  std::vector<symbolic::JacobianMode> modes;
  std::vector<NodeId> minv;
  // "q" / "v" / "a" -> nv x nv row-major partials of RNEA, in the trace graph.
  std::map<std::string, std::vector<NodeId>> rnea_partials;
  std::vector<NodeId> analytic_tau;  // RNEA's value from the analytic sweep (world frame)
  auto analyticPartials = [&](const VecX<Sym>& a) {
    Data<Sym> d(model);
    MatX<Sym> dq, dv, da;
    computeRneaDerivatives(model, d, q_plain, trace->inputs[1], a, dq, dv, da);
    rnea_partials["q"] = tracer.outputs(dq);
    rnea_partials["v"] = tracer.outputs(dv);
    rnea_partials["a"] = tracer.outputs(da);
    analytic_tau = tracer.outputs(d.tau);
  };
  bool a_star_used = false;
  std::uint32_t a_star_first = 0;
  if (aba_analytic && aba_partials_analytic) {
    VecX<Sym> ddq(model.nv);
    for (int i = 0; i < model.nv; ++i) ddq[i] = Sym(g, trace->value[static_cast<std::size_t>(i)]);
    analyticPartials(ddq);
  } else if (aba_analytic) {
    // RNEA traced with its own acceleration input a*, differentiated, a* := ddq after.
    const VecX<Sym> a_star = tracer.addInputs("a_star", model.nv);
    a_star_used = true;
    a_star_first = tracer.block("a_star").first;
    Data<Sym> d2(model);
    const std::vector<NodeId> tau_star = tracer.outputs(rnea(model, d2, trace->inputs[0], trace->inputs[1], a_star));
    // One Jacobian over every q / v block asked for, so its sweeps share their work.
    std::vector<std::string> partial_names;
    for (const char* w : {"q", "v"})
      for (const OutputSpec& o : spec.outputs)
        if (o.kind == OutputKind::Jacobian && std::count(o.wrt.begin(), o.wrt.end(), w) &&
            !std::count(partial_names.begin(), partial_names.end(), w))
          partial_names.push_back(w);
    if (!partial_names.empty()) {
      const symbolic::Jacobian j = symbolic::jacobian(g, tau_star, wrtIndices(partial_names), options.jacobian_mode);
      modes.push_back(j.mode);
      const int n = model.nv;
      for (std::size_t b = 0; b < partial_names.size(); ++b) {
        std::vector<NodeId>& block = rnea_partials[partial_names[b]];
        for (int r = 0; r < n; ++r)
          for (int c = 0; c < n; ++c) block.push_back(j(r, static_cast<int>(b) * n + c));
      }
    }
  } else if (spec.function == ModelFunction::Rnea && rnea_analytic && any_jacobian) {
    analyticPartials(trace->inputs[2]);
  }
  std::vector<NodeId> mass_factors;  // L^T D L of M (lower triangle), n x n row-major
  if (aba_analytic) {
    Data<Sym> d3(model);
    minv = tracer.outputs(computeMinverse(model, d3, q_plain));
    mass_factors = tracer.outputs(d3.M);
  }
  const bool rnea_from_partials = spec.function == ModelFunction::Rnea && !rnea_partials.empty();
  std::vector<symbolic::Hessian> hessians(spec.outputs.size());
  for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
    const OutputSpec& o = spec.outputs[k];
    if (o.kind == OutputKind::Value) {
      trace_outputs[k] = trace->value;
    } else if (o.kind == OutputKind::Jacobian) {
      if (aba_analytic) continue;
      if (rnea_from_partials) {  // the analytic partials, side by side in wrt order
        trace_outputs[k] = sideBySide(rnea_partials, o.wrt, model.nv);
        continue;
      }
      symbolic::Jacobian j = symbolic::jacobian(g, trace->value, wrtIndices(o.wrt), options.jacobian_mode);
      modes.push_back(j.mode);
      trace_outputs[k] = std::move(j.entries);
    } else {
      hessians[k] = o.fixed_weights
                        ? symbolic::weightedHessian(g, trace->value, *o.fixed_weights, wrtIndices(o.wrt),
                                                    options.jacobian_mode)
                        : symbolic::weightedHessian(g, trace->value, trace->weights, wrtIndices(o.wrt),
                                                    options.jacobian_mode);
      modes.push_back(hessians[k].mode);
      trace_outputs[k] = hessians[k].lower;
    }
  }
  built.timings.differentiate_seconds = secondsSince(t_diff);
  built.trace_nodes = g.size();

  // Assemble: the runtime inputs keep their indices, dq is 0, a* is ddq.
  const auto t_assemble = std::chrono::steady_clock::now();
  built.graph = std::make_unique<Graph>();
  Graph& out = *built.graph;
  out.setNodeLimit(options.node_limit);
  std::vector<NodeId> input_map(g.inputCount(), out.zero());
  for (int i = 0; i < runtime_inputs; ++i) input_map[i] = out.input(static_cast<std::uint32_t>(i));
  // The traced value, where an output or the ABA Jacobian uses it.
  const std::vector<NodeId> value =
      rnea_from_partials ? std::vector<NodeId>{} : symbolic::copyCone(g, trace->value, out, input_map);

  std::vector<std::vector<NodeId>> entries(spec.outputs.size());
  if (aba_analytic) {
    const int n = model.nv;
    if (a_star_used)
      for (int i = 0; i < n; ++i) input_map[a_star_first + i] = value[i];
    const std::vector<NodeId> Minv_nodes = symbolic::copyCone(g, minv, out, input_map);
    const std::vector<NodeId> LD = symbolic::copyCone(g, mass_factors, out, input_map);
    std::map<std::string, std::vector<NodeId>> blocks;  // n x n row-major, final graph
    blocks["tau"] = Minv_nodes;
    for (const auto& [w, partial] : rnea_partials) {
      if (w == "a") continue;
      const std::vector<NodeId> D = symbolic::copyCone(g, partial, out, input_map);
      blocks[w] = solveWithMassFactors(out, model, LD, D, n);
    }
    for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
      const OutputSpec& o = spec.outputs[k];
      if (o.kind == OutputKind::Jacobian) entries[k] = sideBySide(blocks, o.wrt, n);
    }
  }
  // RNEA with analytic partials: its value from the same sweep, not a second RNEA.
  const std::vector<NodeId> analytic_value =
      rnea_from_partials ? symbolic::copyCone(g, analytic_tau, out, input_map) : std::vector<NodeId>{};
  for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
    if (spec.outputs[k].kind == OutputKind::Value) entries[k] = rnea_from_partials ? analytic_value : value;
    else if (!trace_outputs[k].empty()) entries[k] = symbolic::copyCone(g, trace_outputs[k], out, input_map);
  }
  const std::vector<std::string> variable_names = trace->variable_names;
  const bool tangent = trace->tangent;
  trace.reset();  // the working graph is no longer needed

  // The function's blocks.
  codegen::FunctionDefinition& def = built.definition;
  def.name = options.name.empty() ? info.name : options.name;
  for (const std::string& name : variable_names)
    def.inputs.push_back({name, static_cast<std::uint32_t>(inputSize(model, name))});
  if (weights_input) def.inputs.push_back({"weights", static_cast<std::uint32_t>(value_size)});
  const std::vector<std::string> names = outputNames(spec);
  for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
    const OutputSpec& o = spec.outputs[k];
    BuiltOutput b;
    b.name = names[k];
    b.kind = o.kind;
    b.wrt = o.wrt;
    b.layout = o.layout;
    int tangent_cols = 0;
    for (const std::string& w : o.wrt) tangent_cols += w == "q" ? model.nv : inputSize(model, w);
    if (o.kind == OutputKind::Value) {
      b.rows = rows, b.cols = cols;
      def.outputs.push_back(codegen::OutputBlock::dense(b.name, rows, cols, entries[k]));
    } else if (o.kind == OutputKind::Jacobian) {
      b.rows = value_size, b.cols = tangent_cols;
      def.outputs.push_back(detail::matrixBlock(b.name, b.rows, b.cols, entries[k], o.layout == Layout::Sparse));
    } else {
      b.rows = b.cols = tangent_cols;
      def.outputs.push_back(detail::hessianBlock(b.name, tangent_cols, entries[k], o.layout == Layout::Sparse, out));
    }
    b.nnz = def.outputs.back().size();
    built.outputs.push_back(std::move(b));
  }
  def.validate(out);

  // In words, for descriptions and benchmarks.
  std::string method = std::string(info.name) + " traced";
  const char* partials = aba_partials_analytic ? "analytic RNEA derivatives" : "differentiated RNEA";
  if (aba_analytic) method += std::string("; Jacobian = -M^-1 d rnea/d(q, v) at a = ddq (") + partials + "), M^-1";
  else if (rnea_from_partials) method += "; Jacobian from analytic RNEA derivatives (Carpentier-Mansard)";
  else if (any_jacobian) method += "; Jacobian by symbolic differentiation";
  if (!modes.empty()) {
    method += " (";
    for (std::size_t k = 0; k < modes.size(); ++k) method += (k ? ", " : "") + std::string(symbolic::toString(modes[k]));
    method += " mode)";
  }
  if (tangent) method += "; q-derivatives in the tangent space";
  built.method = std::move(method);
  built.timings.assemble_seconds = secondsSince(t_assemble);
  return built;
}

}  // namespace

std::size_t builtOperations(const BuiltFunction& f) {
  std::vector<NodeId> outputs;
  for (const codegen::OutputBlock& b : f.definition.outputs) outputs.insert(outputs.end(), b.values.begin(), b.values.end());
  return symbolic::coneSize(*f.graph, outputs).operations;
}

BuiltFunction buildFunction(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options) {
  if (spec.user) return detail::buildUserFunction(model, spec, options);
  const bool rnea_jacobian = spec.function == ModelFunction::Rnea &&
                             std::any_of(spec.outputs.begin(), spec.outputs.end(),
                                         [](const OutputSpec& o) { return o.kind == OutputKind::Jacobian; });
  if (options.rnea_jacobian != RneaJacobianMethod::Cheaper || !rnea_jacobian) {
    FunctionBuilderOptions one = options;
    if (one.rnea_jacobian == RneaJacobianMethod::Cheaper) one.rnea_jacobian = RneaJacobianMethod::Differentiate;
    return buildOneWay(model, spec, one);
  }
  // Both ways (tracing takes milliseconds); a graph past the node limit on one way leaves
  // the other.
  FunctionBuilderOptions analytic = options, differentiated = options;
  analytic.rnea_jacobian = RneaJacobianMethod::Analytic;
  differentiated.rnea_jacobian = RneaJacobianMethod::Differentiate;
  std::optional<BuiltFunction> a, d;
  try {
    a = buildOneWay(model, spec, analytic);
  } catch (const symbolic::GraphTooLarge&) {
  }
  try {
    d = buildOneWay(model, spec, differentiated);
  } catch (const symbolic::GraphTooLarge&) {
    if (!a) throw;
  }
  if (!a) return std::move(*d);
  if (!d) return std::move(*a);
  const std::size_t a_ops = builtOperations(*a), d_ops = builtOperations(*d);
  const bool analytic_kept = static_cast<double>(a_ops) <= kAnalyticRneaOperationsRatio * static_cast<double>(d_ops);
  BuiltFunction& kept = analytic_kept ? *a : *d;
  const BuiltFunction& other = analytic_kept ? *d : *a;
  kept.method += "; chosen over " + std::string(analytic_kept ? "differentiation" : "the analytic derivatives") + " (" +
                 std::to_string(analytic_kept ? a_ops : d_ops) + " operations against " +
                 std::to_string(analytic_kept ? d_ops : a_ops) + ")";
  kept.timings.trace_seconds += other.timings.trace_seconds;
  kept.timings.differentiate_seconds += other.timings.differentiate_seconds;
  kept.timings.assemble_seconds += other.timings.assemble_seconds;
  return std::move(kept);
}

}  // namespace robodiff
