#include "robodiff/symbolic/differentiation.hpp"

#include <algorithm>
#include <optional>
#include <stdexcept>

#include "derivative_rules.hpp"
#include "robodiff/symbolic/cone.hpp"

namespace robodiff::symbolic {
namespace {

constexpr NodeId kNoNode = ~NodeId(0);

// The node of each input index in wrt (kNoNode when the graph has no such input).
std::vector<NodeId> inputNodes(const Graph& g, const std::vector<std::uint32_t>& wrt) {
  std::vector<NodeId> node_of(g.inputCount(), kNoNode);
  for (NodeId id = 0; id < g.size(); ++id)
    if (g.node(id).op == Op::Input) node_of[g.node(id).index] = id;
  std::vector<NodeId> out(wrt.size(), kNoNode);
  for (std::size_t j = 0; j < wrt.size(); ++j)
    if (wrt[j] < node_of.size()) out[j] = node_of[wrt[j]];
  return out;
}

// What a differentiation needs to know about the graph below the outputs: the cone
// of the outputs, and which of its nodes depend on a differentiation input (active).
struct Activity {
  std::vector<char> cone, active;
  NodeId lowest_input = kNoNode;  // no node below it depends on an input
};

Activity activity(const Graph& g, const std::vector<NodeId>& outputs, const std::vector<NodeId>& inputs) {
  Activity a;
  a.cone = coneMask(g, outputs);
  a.active.assign(a.cone.size(), 0);
  for (NodeId in : inputs)
    if (in != kNoNode && in < a.cone.size() && a.cone[in]) {
      a.active[in] = 1;
      a.lowest_input = std::min(a.lowest_input, in);
    }
  if (a.lowest_input == kNoNode) return a;
  for (NodeId id = a.lowest_input; id < a.cone.size(); ++id) {
    if (!a.cone[id] || a.active[id]) continue;
    const Node& n = g.node(id);
    for (int k = 0; k < arity(n.op); ++k)
      if (a.active[n.args[k]]) a.active[id] = 1;
  }
  return a;
}

// Forward sweep: dot holds the seeds (and zero elsewhere from `from` up); fills in the
// tangents of the active nodes above `from`.
void forwardSweep(Graph& g, const Activity& act, NodeId from, std::vector<NodeId>& dot) {
  for (NodeId id = from; id < dot.size(); ++id) {
    if (!act.active[id]) continue;
    const Node n = g.node(id);  // a copy: the graph grows during the sweep
    const int ar = arity(n.op);
    if (ar == 0) continue;
    NodeId t[3] = {0, 0, 0};
    bool any = false;
    for (int k = 0; k < ar; ++k) any |= (t[k] = dot[n.args[k]]) != g.zero();
    if (any) dot[id] = detail::pushTangent(g, id, n, t);
  }
}

// Reverse sweep: bar holds the seeds at or below `top`; propagates every nonzero adjoint
// down to the lowest input. `touched` collects the slots written (to reset them).
void reverseSweep(Graph& g, const Activity& act, NodeId top, std::vector<NodeId>& bar, std::vector<NodeId>& touched) {
  if (act.lowest_input == kNoNode) return;
  for (NodeId id = top + 1; id-- > act.lowest_input;) {
    const NodeId b = bar[id];
    if (b == g.zero() || !act.active[id]) continue;
    const Node n = g.node(id);
    const int ar = arity(n.op);
    if (ar == 0) continue;
    bool wanted[3] = {false, false, false};
    for (int k = 0; k < ar; ++k) wanted[k] = act.active[n.args[k]];
    detail::Term terms[3];
    detail::pullAdjoint(g, id, n, b, wanted, terms);
    for (int k = 0; k < ar; ++k) {
      if (terms[k].node == g.zero()) continue;
      const NodeId arg = n.args[k];
      if (bar[arg] == g.zero()) touched.push_back(arg);
      bar[arg] = detail::accumulate(g, bar[arg], terms[k]);
    }
  }
}

Jacobian forwardJacobian(Graph& g, const std::vector<NodeId>& outputs, const std::vector<NodeId>& inputs) {
  Jacobian jac;
  jac.rows = static_cast<int>(outputs.size());
  jac.cols = static_cast<int>(inputs.size());
  jac.mode = JacobianMode::Forward;
  jac.entries.assign(outputs.size() * inputs.size(), g.zero());
  const Activity act = activity(g, outputs, inputs);
  std::vector<NodeId> dot(act.cone.size(), g.zero());
  for (std::size_t j = 0; j < inputs.size(); ++j) {
    const NodeId in = inputs[j];
    if (in == kNoNode || in >= act.cone.size() || !act.active[in]) continue;
    dot[in] = g.one();
    forwardSweep(g, act, in, dot);
    for (std::size_t i = 0; i < outputs.size(); ++i) jac.entries[i * inputs.size() + j] = dot[outputs[i]];
    std::fill(dot.begin() + in, dot.end(), g.zero());
  }
  return jac;
}

Jacobian reverseJacobian(Graph& g, const std::vector<NodeId>& outputs, const std::vector<NodeId>& inputs) {
  Jacobian jac;
  jac.rows = static_cast<int>(outputs.size());
  jac.cols = static_cast<int>(inputs.size());
  jac.mode = JacobianMode::Reverse;
  jac.entries.assign(outputs.size() * inputs.size(), g.zero());
  const Activity act = activity(g, outputs, inputs);
  std::vector<NodeId> bar(act.cone.size(), g.zero());
  std::vector<NodeId> touched;
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const NodeId out = outputs[i];
    if (!act.active[out]) continue;
    bar[out] = g.one();
    touched.push_back(out);
    reverseSweep(g, act, out, bar, touched);
    for (std::size_t j = 0; j < inputs.size(); ++j)
      if (inputs[j] != kNoNode && inputs[j] < bar.size()) jac.entries[i * inputs.size() + j] = bar[inputs[j]];
    for (NodeId t : touched) bar[t] = g.zero();
    touched.clear();
  }
  return jac;
}

// Sweeps each mode needs: the active inputs (forward) and the active outputs (reverse).
std::pair<std::size_t, std::size_t> sweepCounts(const Graph& g, const std::vector<NodeId>& outputs,
                                                const std::vector<NodeId>& inputs) {
  const Activity act = activity(g, outputs, inputs);
  std::size_t forward = 0, reverse = 0;
  for (NodeId in : inputs) forward += in != kNoNode && in < act.active.size() && act.active[in];
  for (NodeId out : outputs) reverse += act.active[out];
  return {forward, reverse};
}

// Both modes; the one that added fewer nodes is kept. The forward trial runs on a copy
// (the graph is append-only, so the copy keeps every existing id); when it wins, the copy
// replaces the graph. A mode that exceeds the node limit loses.
Jacobian smallerJacobian(Graph& graph, const std::vector<NodeId>& outputs, const std::vector<NodeId>& inputs) {
  const std::size_t before = graph.size();
  Graph trial = graph;
  std::optional<Jacobian> forward;
  try {
    forward = forwardJacobian(trial, outputs, inputs);
  } catch (const GraphTooLarge&) {
  }
  Jacobian reverse;
  try {
    reverse = reverseJacobian(graph, outputs, inputs);
  } catch (const GraphTooLarge&) {
    if (!forward) throw;
    graph = std::move(trial);
    return *forward;
  }
  if (forward && trial.size() - before < graph.size() - before) {
    graph = std::move(trial);
    return *forward;
  }
  return reverse;
}

}  // namespace

const char* toString(JacobianMode mode) {
  switch (mode) {
    case JacobianMode::Automatic: return "automatic";
    case JacobianMode::Forward: return "forward";
    case JacobianMode::Reverse: return "reverse";
    case JacobianMode::Smallest: return "smallest";
  }
  return "?";
}

std::vector<NodeId> Jacobian::nonzeros() const {
  std::vector<NodeId> out;
  for (NodeId e : entries)
    if (e != 0) out.push_back(e);  // row-major order is CSR order
  return out;
}

Jacobian jacobian(Graph& graph, const std::vector<NodeId>& outputs, const std::vector<std::uint32_t>& wrt,
                  JacobianMode mode) {
  for (NodeId o : outputs)
    if (o >= graph.size()) throw std::out_of_range("jacobian: output node " + std::to_string(o) + " is not in the graph");
  const std::vector<NodeId> inputs = inputNodes(graph, wrt);
  if (mode == JacobianMode::Forward) return forwardJacobian(graph, outputs, inputs);
  if (mode == JacobianMode::Reverse) return reverseJacobian(graph, outputs, inputs);
  if (mode == JacobianMode::Automatic) {
    const auto [forward_sweeps, reverse_sweeps] = sweepCounts(graph, outputs, inputs);
    if (forward_sweeps < reverse_sweeps) return forwardJacobian(graph, outputs, inputs);
    if (reverse_sweeps < forward_sweeps) return reverseJacobian(graph, outputs, inputs);
  }
  return smallerJacobian(graph, outputs, inputs);
}

std::vector<NodeId> directionalDerivative(Graph& graph, const std::vector<NodeId>& outputs,
                                          const std::vector<std::uint32_t>& wrt, const std::vector<NodeId>& direction) {
  if (direction.size() != wrt.size()) throw std::invalid_argument("directionalDerivative: direction and wrt differ in size");
  const std::vector<NodeId> inputs = inputNodes(graph, wrt);
  const Activity act = activity(graph, outputs, inputs);
  std::vector<NodeId> dot(act.cone.size(), graph.zero());
  for (std::size_t j = 0; j < inputs.size(); ++j)
    if (inputs[j] != kNoNode && inputs[j] < dot.size() && act.active[inputs[j]])
      dot[inputs[j]] = detail::accumulate(graph, dot[inputs[j]], {direction[j], false});
  if (act.lowest_input != kNoNode) forwardSweep(graph, act, act.lowest_input, dot);
  std::vector<NodeId> out;
  out.reserve(outputs.size());
  for (NodeId o : outputs) out.push_back(dot[o]);
  return out;
}

std::vector<NodeId> weightedGradient(Graph& graph, const std::vector<NodeId>& outputs, const std::vector<NodeId>& weights,
                                     const std::vector<std::uint32_t>& wrt) {
  if (weights.size() != outputs.size()) throw std::invalid_argument("weightedGradient: weights and outputs differ in size");
  const std::vector<NodeId> inputs = inputNodes(graph, wrt);
  const Activity act = activity(graph, outputs, inputs);
  std::vector<NodeId> bar(act.cone.size(), graph.zero());
  std::vector<NodeId> touched;
  NodeId top = 0;
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    if (!act.active[outputs[i]]) continue;
    bar[outputs[i]] = detail::accumulate(graph, bar[outputs[i]], {weights[i], false});
    top = std::max(top, outputs[i]);
  }
  reverseSweep(graph, act, top, bar, touched);
  std::vector<NodeId> out(wrt.size(), graph.zero());
  for (std::size_t j = 0; j < inputs.size(); ++j)
    if (inputs[j] != kNoNode && inputs[j] < bar.size()) out[j] = bar[inputs[j]];
  return out;
}

std::vector<NodeId> gradient(Graph& graph, NodeId output, const std::vector<std::uint32_t>& wrt) {
  return weightedGradient(graph, {output}, {graph.one()}, wrt);
}

}  // namespace robodiff::symbolic
