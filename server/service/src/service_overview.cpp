// The dashboard's snapshot: models, functions with their compile state and timings,
// failed builds, jobs, and the metrics with fine latency histograms.
#include <algorithm>

#include "robodiff/server/service.hpp"
#include "service_state.hpp"

namespace robodiff::server {
namespace {

// "value, jacobian[q,v,a]": what a function answers, in a few words.
std::string describeOutputs(const FunctionSpec& spec) {
  std::string out;
  for (const OutputSpec& o : spec.outputs) {
    if (!out.empty()) out += ", ";
    out += toString(o.kind);
    if (!o.wrt.empty()) {
      out += '[';
      for (std::size_t i = 0; i < o.wrt.size(); ++i) out += (i ? "," : "") + o.wrt[i];
      out += ']';
    }
    if (o.layout == Layout::Sparse) out += " sparse";
  }
  if (!spec.frame.empty()) out += " @" + spec.frame;
  return out;
}

// The dashboard's one word for where a function stands.
const char* phaseOf(const detail::FunctionEntry& f) {
  switch (f.state()) {
    case rpc::FunctionState::Building: return "tracing";
    case rpc::FunctionState::Failed: return "failed";
    case rpc::FunctionState::Ready: break;
  }
  if (f.compiled()) return "compiled";
  switch (f.compileStage()) {
    case detail::CompileStage::Fetching: return "fetching";
    case detail::CompileStage::Queued: return "queued";
    case detail::CompileStage::Compiling: return "compiling";
    case detail::CompileStage::Failed: return "build-failed";
    case detail::CompileStage::None:
    case detail::CompileStage::Compiled: break;  // Compiled without a compiled evaluator: not swapped in yet
  }
  return "interpreted";
}

// A loaded model as the dashboard lists it.
ServiceOverview::Model modelRow(const detail::Registry::ModelView& view) {
  const detail::ModelEntry& m = *view.model;
  ServiceOverview::Model out;
  out.id = m.id;
  out.name = m.displayName();
  out.floating_base = m.floating_base;
  out.nq = static_cast<std::uint32_t>(m.model->nq);
  out.nv = static_cast<std::uint32_t>(m.model->nv);
  out.joints = static_cast<std::uint32_t>(m.joint_names.size());
  out.frames = static_cast<std::uint32_t>(m.frame_names.size());
  out.references = view.references;
  out.functions = view.functions;
  return out;
}

// A loaded function as the dashboard lists it: its phase, its evaluations' figures and
// how long it took to build.
ServiceOverview::Function functionRow(const detail::Registry::FunctionView& view) {
  const detail::FunctionEntry& f = *view.function;
  ServiceOverview::Function out;
  out.id = f.id();
  out.model_id = f.model().id;
  out.model_name = f.model().displayName();
  out.function = f.functionName();
  out.outputs = describeOutputs(f.spec());
  out.phase = phaseOf(f);
  out.message = f.message();
  out.references = view.references;
  out.evaluations = f.evaluations();
  const detail::EvaluationFigures e = f.evaluationFigures();
  out.calls = e.calls;
  out.p50_ns = e.p50_ns;
  out.p99_ns = e.p99_ns;
  out.max_ns = e.max_ns;
  out.batch_calls = e.batch_calls;
  out.batch_knots = e.batch_knots;
  out.batch_ns = e.batch_ns;
  const detail::BuildTimes t = f.buildTimes();
  out.trace_seconds = t.trace_seconds;
  out.compile_seconds = t.compile_seconds;
  out.from_cache = t.from_cache;
  return out;
}

// A recent failed build as the dashboard lists it.
ServiceOverview::BuildFailure failureRow(const detail::BuildFailureRecord& r) {
  ServiceOverview::BuildFailure out;
  out.unix_seconds = std::chrono::duration<double>(r.when.time_since_epoch()).count();
  out.function_id = r.function_id;
  out.model = r.model;
  out.function = r.function;
  out.message = r.message;
  out.stage = detail::toString(r.stage);
  out.interpreter_serves = r.interpreter_serves();
  return out;
}

}  // namespace

std::vector<ServiceOverview::MethodLatency> Service::requestLatencies() const {
  std::vector<ServiceOverview::MethodLatency> out;
  for (std::uint32_t i = 0; i < rpc::kMethodCount; ++i) {
    const auto method = static_cast<rpc::Method>(i);
    out.push_back({method, state_->stats.latency(method).occupied()});
  }
  return out;
}

ServiceOverview Service::overview(std::size_t max_jobs) const {
  State& s = *state_;
  ServiceOverview o;
  o.instance_id = s.instance_id;
  o.version = s.options.version;
  o.metrics = metrics();
  o.methods = s.stats.methods();
  o.latencies = requestLatencies();
  for (const detail::Registry::ModelView& view : s.registry.modelViews()) o.models.push_back(modelRow(view));
  for (const detail::Registry::FunctionView& view : s.registry.functionViews()) o.functions.push_back(functionRow(view));
  for (const detail::BuildFailureRecord& r : s.builds.recentFailures()) o.build_failures.push_back(failureRow(r));
  if (s.jobs) {
    try {
      o.jobs = s.jobs->recent(max_jobs);
    } catch (const std::exception& e) {
      o.jobs_error = e.what();
    }
  }
  return o;
}

}  // namespace robodiff::server
