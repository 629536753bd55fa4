#include "function_entry.hpp"

namespace robodiff::server::detail {

const char* toString(CompileStage stage) {
  switch (stage) {
    case CompileStage::None: return "none";
    case CompileStage::Fetching: return "fetching";
    case CompileStage::Queued: return "queued";
    case CompileStage::Compiling: return "compiling";
    case CompileStage::Compiled: return "compiled";
    case CompileStage::Failed: return "failed";
  }
  return "unknown";
}

FunctionEntry::FunctionEntry(std::string id, std::shared_ptr<const ModelEntry> model, FunctionSpec spec,
                             std::string spec_text, std::uint64_t sequence)
    : id_(std::move(id)),
      model_(std::move(model)),
      spec_(std::move(spec)),
      spec_text_(std::move(spec_text)),
      sequence_(sequence) {}

bool FunctionEntry::compiled() const {
  const std::shared_ptr<const Evaluator> e = evaluator();
  return e && e->compiled();
}

void FunctionEntry::ready(std::shared_ptr<const Evaluator> evaluator) {
  {
    std::lock_guard lock(mutex_);
    if (state() != rpc::FunctionState::Building) return;
    evaluator_.store(std::move(evaluator), std::memory_order_release);
    state_.store(rpc::FunctionState::Ready, std::memory_order_release);
  }
  settled_.notify_all();
}

void FunctionEntry::swap(std::shared_ptr<const Evaluator> evaluator) {
  {
    std::lock_guard lock(mutex_);
    if (state() == rpc::FunctionState::Failed) return;
    evaluator_.store(std::move(evaluator), std::memory_order_release);
    if (state() == rpc::FunctionState::Ready) return;
    state_.store(rpc::FunctionState::Ready, std::memory_order_release);
  }
  settled_.notify_all();
}

void FunctionEntry::fail(StatusCode code, std::string message) {
  {
    std::lock_guard lock(mutex_);
    if (state() != rpc::FunctionState::Building) return;
    failure_ = Status{code, message};
    message_ = std::move(message);
    state_.store(rpc::FunctionState::Failed, std::memory_order_release);
  }
  settled_.notify_all();
}

Status FunctionEntry::failure() const {
  std::lock_guard lock(mutex_);
  return failure_;
}

void FunctionEntry::setMessage(std::string message) {
  std::lock_guard lock(mutex_);
  message_ = std::move(message);
}

std::string FunctionEntry::message() const {
  std::lock_guard lock(mutex_);
  return message_;
}

bool FunctionEntry::waitSettled(Clock::time_point deadline) const {
  std::unique_lock lock(mutex_);
  auto settled = [this] { return state() != rpc::FunctionState::Building; };
  if (deadline == Clock::time_point::max()) {
    settled_.wait(lock, settled);
    return true;
  }
  return settled_.wait_until(lock, deadline, settled);
}

EvaluationFigures FunctionEntry::evaluationFigures() const {
  EvaluationFigures f;
  f.calls = call_latency_.count();
  f.p50_ns = call_latency_.percentile(0.5);
  f.p99_ns = call_latency_.percentile(0.99);
  f.max_ns = call_latency_.max();
  f.batch_calls = batch_calls_.load(std::memory_order_relaxed);
  f.batch_knots = batch_knots_.load(std::memory_order_relaxed);
  f.batch_ns = batch_ns_.load(std::memory_order_relaxed);
  return f;
}

BuildTimes FunctionEntry::buildTimes() const {
  std::lock_guard lock(mutex_);
  return build_times_;
}

void FunctionEntry::setTraceSeconds(double seconds) {
  std::lock_guard lock(mutex_);
  build_times_.trace_seconds = seconds;
}

void FunctionEntry::setCompileSeconds(double seconds, bool from_cache) {
  std::lock_guard lock(mutex_);
  build_times_.compile_seconds = seconds;
  build_times_.from_cache = from_cache;
}

void FunctionEntry::setCacheKey(std::string key) {
  std::lock_guard lock(mutex_);
  cache_key_ = std::move(key);
}

std::string FunctionEntry::cacheKey() const {
  std::lock_guard lock(mutex_);
  return cache_key_;
}

}  // namespace robodiff::server::detail
