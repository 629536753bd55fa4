#include "model_function_build.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <set>

#include "robodiff/dynamics/aba_derivatives.hpp"
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
#include "user_primitive_rules.hpp"

namespace robodiff::detail {

using symbolic::Graph;
using symbolic::NodeId;
using symbolic::Sym;

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

// The steps of one build, sharing what they compute. The working trace lives in a graph
// that may also hold helper inputs the assembled function does not have (the tangent
// displacement dq, ABA's a*); assembling copies what the outputs use into a fresh graph.
class ModelFunctionBuild {
 public:
  ModelFunctionBuild(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options)
      : model_(model), spec_(spec), options_(options), info_(functionInfo(spec.function)) {
    const auto [rows, cols] = valueShape(model, spec.function);
    rows_ = rows, cols_ = cols, value_size_ = rows * cols;
    graph_.setNodeLimit(options.node_limit);
  }

  BuiltFunction run() {
    checkAgainstModel();
    auto t = std::chrono::steady_clock::now();
    traceValue();
    built_.timings.trace_seconds = secondsSince(t);
    t = std::chrono::steady_clock::now();
    differentiate();
    built_.timings.differentiate_seconds = secondsSince(t);
    built_.trace_nodes = graph_.size();
    t = std::chrono::steady_clock::now();
    built_.graph = std::make_unique<Graph>();
    built_.graph->setNodeLimit(options_.node_limit);
    const std::vector<std::vector<NodeId>> entries = assemble(*built_.graph);
    graph_ = Graph();  // the working trace, often the build's largest graph, goes before the blocks are made
    defineOutputs(entries);
    built_.method = method();
    built_.timings.assemble_seconds = secondsSince(t);
    return std::move(built_);
  }

 private:
  // Checks the parser could not make without the model; notes whether a Hessian takes its
  // weights as an input and which inputs derivatives are taken against.
  void checkAgainstModel() {
    for (const InputSpec& in : spec_.inputs)
      if (in.fixed && static_cast<int>(in.fixed->size()) != inputSize(model_, in.name))
        throw SpecError("inputs." + in.name + ".fixed: " + std::to_string(in.fixed->size()) + " numbers, but " +
                        (model_.name.empty() ? "the model" : model_.name) + " has " + (in.name == "q" ? "nq" : "nv") +
                        " = " + std::to_string(inputSize(model_, in.name)));
    bool hessian = false;
    for (std::size_t k = 0; k < spec_.outputs.size(); ++k) {
      const OutputSpec& o = spec_.outputs[k];
      for (const std::string& w : o.wrt) wrt_needed_.insert(w);
      any_jacobian_ = any_jacobian_ || o.kind == OutputKind::Jacobian;
      if (o.kind != OutputKind::Hessian) continue;
      hessian = true;
      if (o.fixed_weights && static_cast<int>(o.fixed_weights->size()) != value_size_)
        throw SpecError("outputs[" + std::to_string(k) + "].weights: " + std::to_string(o.fixed_weights->size()) +
                        " numbers, but the value of " + info_.name + " has " + std::to_string(value_size_) +
                        " entries");
      if (!o.fixed_weights) weights_input_ = true;
    }
    aba_partials_analytic_ = options_.aba_rnea_partials == RneaJacobianMethod::Analytic;
    // ABA's Jacobian from RNEA's partials at a = ddq.
    aba_analytic_ = spec_.function == ModelFunction::Aba && options_.aba_jacobian == AbaJacobianMethod::Analytic &&
                    any_jacobian_;
    // ... and its value from the same sweep, unless a Hessian differentiates the traced value.
    aba_from_sweep_ = aba_analytic_ && aba_partials_analytic_ && !hessian;
  }

  // The model function on symbolic inputs (fixed ones as constants), q moved by dq where
  // q-derivatives must be taken in the tangent space (a free-flyer's).
  void traceValue() {
    for (const std::string& name : info_.inputs) {
      const InputSpec& in = spec_.input(name);
      if (in.fixed) {
        inputs_.push_back(Eigen::Map<const Eigen::VectorXd>(in.fixed->data(), in.fixed->size()).cast<Sym>());
      } else {
        inputs_.push_back(tracer_.addInputs(name, inputSize(model_, name)));
        variable_names_.push_back(name);
      }
    }
    if (weights_input_) weights_ = tracer_.outputs(tracer_.addInputs("weights", value_size_));
    runtime_inputs_ = static_cast<int>(graph_.inputCount());
    tangent_ = !spec_.input("q").fixed && hasFreeFlyer(model_) && wrt_needed_.count("q");
    q_plain_ = inputs_[0];  // analytic derivatives are tangent already
    if (tangent_) inputs_[0] = symbolic::integrateSecondOrder(model_, inputs_[0], tracer_.addInputs("dq", model_.nv));
    Data<Sym> data(model_);
    if (abaByFactors())
      value_ = tracer_.outputs(forwardDynamicsByFactors(model_, data, inputs_[0], inputs_[1], inputs_[2]));
    else
      value_ = tracer_.outputs(modelFunctionValue(model_, data, spec_, resolveFrame(model_, spec_), inputs_));
  }

  bool abaByFactors() const {
    return spec_.function == ModelFunction::Aba && options_.aba_value == AbaValueMethod::Factors;
  }

  // The tangent columns of named inputs (q -> dq when moving on the manifold).
  std::vector<std::uint32_t> wrtIndices(const std::vector<std::string>& names) {
    std::vector<std::string> blocks;
    for (const std::string& n : names) blocks.push_back(n == "q" && tangent_ ? "dq" : n);
    return tracer_.indices(blocks);
  }

  void differentiate() {
    rneaPartials();
    if (aba_analytic_ && !aba_from_sweep_) {
      Data<Sym> d(model_);
      // World-frame M: it shares oMi and the subspace columns with RNEA's partials.
      minv_ = tracer_.outputs(computeMinverse(model_, d, q_plain_, CrbaFrame::World));
      mass_factors_ = tracer_.outputs(d.M);  // L^T D L of M (lower triangle), n x n row-major
    }
    rnea_from_partials_ = spec_.function == ModelFunction::Rnea && !rnea_partials_.empty();
    trace_outputs_.resize(spec_.outputs.size());
    for (std::size_t k = 0; k < spec_.outputs.size(); ++k) traceOutput(k);
  }

  // The partials of RNEA the Jacobians are made of: analytic (Carpentier-Mansard) for an
  // RNEA Jacobian or ABA's at a = ddq, or RNEA traced with its own acceleration a* and
  // differentiated (a* := ddq when assembling).
  void rneaPartials() {
    if (aba_from_sweep_) {
      abaFromSweep();
    } else if (aba_analytic_ && aba_partials_analytic_) {
      VecX<Sym> ddq(model_.nv);
      for (int i = 0; i < model_.nv; ++i) ddq[i] = Sym(graph_, value_[static_cast<std::size_t>(i)]);
      analyticPartials(ddq);
    } else if (aba_analytic_) {
      differentiatedPartials();
    } else if (spec_.function == ModelFunction::Rnea && options_.rnea_jacobian == RneaJacobianMethod::Analytic &&
               any_jacobian_) {
      analyticPartials(inputs_[2]);
    }
  }

  void analyticPartials(const VecX<Sym>& a) {
    Data<Sym> d(model_);
    MatX<Sym> dq, dv, da;
    computeRneaDerivatives(model_, d, q_plain_, inputs_[1], a, dq, dv, da);
    rnea_partials_["q"] = tracer_.outputs(dq);
    rnea_partials_["v"] = tracer_.outputs(dv);
    rnea_partials_["a"] = tracer_.outputs(da);
    analytic_tau_ = tracer_.outputs(d.tau);
  }

  // ABA's value, RNEA's partials at a = ddq and M's factors from one world-frame sweep
  // (dynamics/aba_derivatives.hpp); the traced ABA is left unused.
  void abaFromSweep() {
    Data<Sym> d(model_);
    const AbaDerivativeTerms<Sym> t = computeAbaDerivativeTerms(model_, d, q_plain_, inputs_[1], inputs_[2]);
    value_ = tracer_.outputs(t.ddq);
    rnea_partials_["q"] = tracer_.outputs(t.dtau_dq);
    rnea_partials_["v"] = tracer_.outputs(t.dtau_dv);
    mass_factors_ = tracer_.outputs(t.mass_factors);
    minv_ = tracer_.outputs(inverseFromFactors(dofParents(model_), t.mass_factors));
  }

  void differentiatedPartials() {
    const VecX<Sym> a_star = tracer_.addInputs("a_star", model_.nv);
    a_star_used_ = true;
    a_star_first_ = tracer_.block("a_star").first;
    Data<Sym> d(model_);
    const std::vector<NodeId> tau_star = tracer_.outputs(rnea(model_, d, inputs_[0], inputs_[1], a_star));
    // One Jacobian over every q / v block asked for, so its sweeps share their work.
    std::vector<std::string> names;
    for (const char* w : {"q", "v"})
      for (const OutputSpec& o : spec_.outputs)
        if (o.kind == OutputKind::Jacobian && std::count(o.wrt.begin(), o.wrt.end(), w) &&
            !std::count(names.begin(), names.end(), w))
          names.push_back(w);
    if (names.empty()) return;
    const symbolic::Jacobian j = symbolic::jacobian(graph_, tau_star, wrtIndices(names), options_.jacobian_mode);
    modes_.push_back(j.mode);
    const int n = model_.nv;
    for (std::size_t b = 0; b < names.size(); ++b) {
      std::vector<NodeId>& block = rnea_partials_[names[b]];
      for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) block.push_back(j(r, static_cast<int>(b) * n + c));
    }
  }

  // Output k's nodes in the trace graph (none for the analytic ABA Jacobian: assembled
  // from the partials in the final graph).
  void traceOutput(std::size_t k) {
    const OutputSpec& o = spec_.outputs[k];
    if (o.kind == OutputKind::Value) {
      trace_outputs_[k] = value_;
    } else if (o.kind == OutputKind::Jacobian) {
      if (aba_analytic_) return;
      if (rnea_from_partials_) {  // the analytic partials, side by side in wrt order
        trace_outputs_[k] = sideBySide(rnea_partials_, o.wrt, model_.nv);
        return;
      }
      symbolic::Jacobian j = symbolic::jacobian(graph_, value_, wrtIndices(o.wrt), options_.jacobian_mode);
      modes_.push_back(j.mode);
      trace_outputs_[k] = std::move(j.entries);
    } else {
      const symbolic::Hessian h =
          o.fixed_weights
              ? symbolic::weightedHessian(graph_, value_, *o.fixed_weights, wrtIndices(o.wrt), options_.jacobian_mode)
              : symbolic::weightedHessian(graph_, value_, weights_, wrtIndices(o.wrt), options_.jacobian_mode);
      modes_.push_back(h.mode);
      trace_outputs_[k] = h.lower;
    }
  }

  // Copies what the outputs use into `out`: the runtime inputs keep their indices, dq is
  // 0, a* is ddq. Returns each output's entries in `out`.
  std::vector<std::vector<NodeId>> assemble(Graph& out) {
    input_map_.assign(graph_.inputCount(), out.zero());
    for (int i = 0; i < runtime_inputs_; ++i) input_map_[i] = out.input(static_cast<std::uint32_t>(i));
    // The traced value, where an output or the ABA Jacobian uses it.
    const std::vector<NodeId> value =
        rnea_from_partials_ ? std::vector<NodeId>{} : symbolic::copyCone(graph_, value_, out, input_map_);
    std::vector<std::vector<NodeId>> entries(spec_.outputs.size());
    if (aba_analytic_) abaJacobians(out, value, entries);
    // RNEA with analytic partials: its value from the same sweep, not a second RNEA.
    const std::vector<NodeId> analytic_value =
        rnea_from_partials_ ? symbolic::copyCone(graph_, analytic_tau_, out, input_map_) : std::vector<NodeId>{};
    for (std::size_t k = 0; k < spec_.outputs.size(); ++k) {
      if (spec_.outputs[k].kind == OutputKind::Value) entries[k] = rnea_from_partials_ ? analytic_value : value;
      else if (!trace_outputs_[k].empty()) entries[k] = symbolic::copyCone(graph_, trace_outputs_[k], out, input_map_);
    }
    return entries;
  }

  // ABA's Jacobians in the final graph: d ddq/d tau = M^-1, d ddq/d(q, v) = -M^-1 d rnea/d(q, v).
  void abaJacobians(Graph& out, const std::vector<NodeId>& value, std::vector<std::vector<NodeId>>& entries) {
    const int n = model_.nv;
    if (a_star_used_)
      for (int i = 0; i < n; ++i) input_map_[a_star_first_ + i] = value[i];
    const std::vector<NodeId> LD = symbolic::copyCone(graph_, mass_factors_, out, input_map_);
    std::map<std::string, std::vector<NodeId>> blocks;  // n x n row-major, final graph
    blocks["tau"] = symbolic::copyCone(graph_, minv_, out, input_map_);
    for (const auto& [w, partial] : rnea_partials_) {
      if (w == "a") continue;
      blocks[w] = solveWithMassFactors(out, model_, LD, symbolic::copyCone(graph_, partial, out, input_map_), n);
    }
    for (std::size_t k = 0; k < spec_.outputs.size(); ++k)
      if (spec_.outputs[k].kind == OutputKind::Jacobian) entries[k] = sideBySide(blocks, spec_.outputs[k].wrt, n);
  }

  // The function's inputs and output blocks.
  void defineOutputs(const std::vector<std::vector<NodeId>>& entries) {
    codegen::FunctionDefinition& def = built_.definition;
    Graph& out = *built_.graph;
    def.name = options_.name.empty() ? info_.name : options_.name;
    for (const std::string& name : variable_names_)
      def.inputs.push_back({name, static_cast<std::uint32_t>(inputSize(model_, name))});
    if (weights_input_) def.inputs.push_back({"weights", static_cast<std::uint32_t>(value_size_)});
    const std::vector<std::string> names = outputNames(spec_);
    built_.value_rows = rows_;
    built_.value_cols = cols_;
    for (std::size_t k = 0; k < spec_.outputs.size(); ++k) {
      const OutputSpec& o = spec_.outputs[k];
      BuiltOutput b;
      b.name = names[k];
      b.kind = o.kind;
      b.wrt = o.wrt;
      b.layout = o.layout;
      int tangent_cols = 0;
      for (const std::string& w : o.wrt) tangent_cols += w == "q" ? model_.nv : inputSize(model_, w);
      const bool sparse = o.layout == Layout::Sparse;
      if (o.kind == OutputKind::Value) {
        b.rows = rows_, b.cols = cols_;
        def.outputs.push_back(codegen::OutputBlock::dense(b.name, rows_, cols_, entries[k]));
      } else if (o.kind == OutputKind::Jacobian) {
        b.rows = value_size_, b.cols = tangent_cols;
        def.outputs.push_back(matrixBlock(b.name, b.rows, b.cols, entries[k], sparse));
      } else {
        b.rows = b.cols = tangent_cols;
        def.outputs.push_back(hessianBlock(b.name, tangent_cols, entries[k], sparse, out));
      }
      b.nnz = def.outputs.back().size();
      built_.outputs.push_back(std::move(b));
    }
    def.validate(out);
  }

  // In words, for descriptions and benchmarks.
  std::string method() const {
    std::string m = aba_from_sweep_ ? std::string("aba = M^-1 (tau - nle) from the sweep of its derivatives")
                    : abaByFactors()  ? std::string("aba = M^-1 (tau - nle) by M's tree factors (rnea at a = 0, crba)")
                                      : std::string(info_.name) + " traced";
    const char* partials = aba_partials_analytic_ ? "analytic RNEA derivatives" : "differentiated RNEA";
    if (aba_analytic_) m += std::string("; Jacobian = -M^-1 d rnea/d(q, v) at a = ddq (") + partials + "), M^-1";
    else if (rnea_from_partials_) m += "; Jacobian from analytic RNEA derivatives (Carpentier-Mansard)";
    else if (any_jacobian_) m += "; Jacobian by symbolic differentiation";
    if (!modes_.empty()) {
      m += " (";
      for (std::size_t k = 0; k < modes_.size(); ++k) m += (k ? ", " : "") + std::string(symbolic::toString(modes_[k]));
      m += " mode)";
    }
    if (tangent_) m += "; q-derivatives in the tangent space";
    return m;
  }

  const Model& model_;
  const FunctionSpec& spec_;
  const FunctionBuilderOptions& options_;
  const FunctionInfo& info_;
  int rows_ = 0, cols_ = 0, value_size_ = 0;
  // What the spec asks for.
  bool weights_input_ = false, any_jacobian_ = false, aba_analytic_ = false, aba_partials_analytic_ = false,
       aba_from_sweep_ = false;
  std::set<std::string> wrt_needed_;
  // The working trace.
  Graph graph_;
  symbolic::Tracer tracer_{graph_};
  std::vector<VecX<Sym>> inputs_;  // every function input (fixed ones as constants), q moved by dq
  VecX<Sym> q_plain_;              // q before the move
  std::vector<std::string> variable_names_;
  int runtime_inputs_ = 0;
  bool tangent_ = false;         // q-derivatives are taken w.r.t. the block "dq"
  std::vector<NodeId> value_;    // row-major
  std::vector<NodeId> weights_;  // the "weights" block, when a Hessian takes them as input
  // The derivatives, in the trace graph.
  std::map<std::string, std::vector<NodeId>> rnea_partials_;  // "q" / "v" / "a" -> nv x nv row-major
  std::vector<NodeId> analytic_tau_;  // RNEA's value from the analytic sweep
  bool a_star_used_ = false, rnea_from_partials_ = false;
  std::uint32_t a_star_first_ = 0;
  std::vector<NodeId> minv_, mass_factors_;
  std::vector<std::vector<NodeId>> trace_outputs_;
  std::vector<symbolic::JacobianMode> modes_;
  // Assembling: the trace graph's inputs in the final graph.
  std::vector<NodeId> input_map_;
  BuiltFunction built_;
};

}  // namespace

BuiltFunction buildModelFunction(const Model& model, const FunctionSpec& spec, const FunctionBuilderOptions& options) {
  return ModelFunctionBuild(model, spec, options).run();
}

}  // namespace robodiff::detail
