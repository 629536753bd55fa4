#pragma once
// One function of one model, from GetFunction to its release: BUILDING until traced (or
// found in the cache), then READY served by an evaluator, or FAILED with the reason.
// While READY the evaluator may be replaced once (the compiled library takes over from
// the interpreter): evaluations load it atomically and keep what they loaded alive.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "evaluator.hpp"
#include "holders.hpp"
#include "latency_histogram.hpp"
#include "model_entry.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/schema/messages.hpp"
#include "robodiff/server/service_api.hpp"

namespace robodiff::server::detail {

// Where a READY function's compiled library stands (the dashboard's compile state).
enum class CompileStage : std::uint8_t {
  None,       // no library coming: compiling is off, or not decided yet
  Fetching,   // asking the fleet's build hosts for it (the interpreter serves meanwhile)
  Queued,     // waiting for a build worker
  Compiling,  // a worker builds it
  Compiled,   // the library serves (built here, or found in the cache)
  Failed,     // the build failed; the interpreter keeps serving (message() says why)
};
const char* toString(CompileStage stage);  // "none", "queued", ...

// How long making it servable took; -1 where it did not happen (yet).
struct BuildTimes {
  double trace_seconds = -1;
  double compile_seconds = -1;
  bool from_cache = false;  // the library was found in the cache, not built for this request
};

// Evaluations as the service timed them (around the evaluator, checks included).
struct EvaluationFigures {
  std::uint64_t calls = 0;  // single Evaluate calls
  std::uint64_t p50_ns = 0, p99_ns = 0, max_ns = 0;
  std::uint64_t batch_calls = 0, batch_knots = 0, batch_ns = 0;
};

class FunctionEntry {
 public:
  FunctionEntry(std::string id, std::shared_ptr<const ModelEntry> model, FunctionSpec spec, std::string spec_text,
                std::uint64_t sequence);

  const std::string& id() const { return id_; }
  const ModelEntry& model() const { return *model_; }
  const std::shared_ptr<const ModelEntry>& modelEntry() const { return model_; }
  const FunctionSpec& spec() const { return spec_; }
  const std::string& specText() const { return spec_text_; }
  std::string functionName() const { return spec_.functionName(); }  // "rnea", or a user function's name
  std::uint64_t sequence() const { return sequence_; }                   // order of creation

  rpc::FunctionState state() const { return state_.load(std::memory_order_acquire); }
  // The evaluator serving it; null unless READY.
  std::shared_ptr<const Evaluator> evaluator() const { return evaluator_.load(std::memory_order_acquire); }
  bool compiled() const;

  // BUILDING -> READY. Ignored unless BUILDING.
  void ready(std::shared_ptr<const Evaluator> evaluator);
  // The compiled library serves from now on: it replaces the interpreter of a READY
  // function, or makes a BUILDING one READY (a robot's library that arrived while the
  // interpreter was still being traced; the later ready() is then ignored). Ignored for a
  // FAILED function.
  void swap(std::shared_ptr<const Evaluator> evaluator);
  // BUILDING -> FAILED with the status GetFunction replies. Ignored unless BUILDING.
  void fail(StatusCode code, std::string message);

  // FAILED: why (code and message). READY: OK.
  Status failure() const;
  // A note for ListFunctions (a failed build while the interpreter serves, ...).
  void setMessage(std::string message);
  std::string message() const;

  // Waits until READY or FAILED, or the deadline; true when settled.
  bool waitSettled(Clock::time_point deadline) const;

  // Knots evaluated.
  void countEvaluations(std::uint64_t knots) { evaluations_.fetch_add(knots, std::memory_order_relaxed); }
  std::uint64_t evaluations() const { return evaluations_.load(std::memory_order_relaxed); }
  // Timings of single calls and batches (lock-free; a few instructions each).
  void recordCall(std::uint64_t ns) { call_latency_.record(ns); }
  void recordBatch(std::uint64_t knots, std::uint64_t ns) {
    batch_calls_.fetch_add(1, std::memory_order_relaxed);
    batch_knots_.fetch_add(knots, std::memory_order_relaxed);
    batch_ns_.fetch_add(ns, std::memory_order_relaxed);
  }
  EvaluationFigures evaluationFigures() const;

  CompileStage compileStage() const { return compile_stage_.load(std::memory_order_acquire); }
  void setCompileStage(CompileStage stage) { compile_stage_.store(stage, std::memory_order_release); }
  BuildTimes buildTimes() const;
  void setTraceSeconds(double seconds);
  void setCompileSeconds(double seconds, bool from_cache);

  // The cache key of the library serving it (set before it serves); empty before.
  void setCacheKey(std::string key);
  std::string cacheKey() const;
  // One rebuild of a lost cache entry at a time (FunctionBuilds::refillIfMissing): true
  // for the caller that may start one, until endRefill().
  bool beginRefill() { return !refilling_.exchange(true, std::memory_order_acq_rel); }
  void endRefill() { refilling_.store(false, std::memory_order_release); }

  // Released (no references left): builds not started yet are skipped.
  void markUnloaded() { unloaded_.store(true, std::memory_order_release); }
  bool unloaded() const { return unloaded_.load(std::memory_order_acquire); }

  // GetFunction calls not yet released, per caller. Guarded by the registry's mutex.
  Holders holders;

 private:
  const std::string id_;
  const std::shared_ptr<const ModelEntry> model_;
  const FunctionSpec spec_;
  const std::string spec_text_;
  const std::uint64_t sequence_;

  std::atomic<rpc::FunctionState> state_{rpc::FunctionState::Building};
  std::atomic<std::shared_ptr<const Evaluator>> evaluator_;
  std::atomic<std::uint64_t> evaluations_{0};
  std::atomic<bool> unloaded_{false};
  std::atomic<bool> refilling_{false};
  std::atomic<CompileStage> compile_stage_{CompileStage::None};
  LatencyHistogram call_latency_;
  std::atomic<std::uint64_t> batch_calls_{0}, batch_knots_{0}, batch_ns_{0};

  mutable std::mutex mutex_;  // the failure, the message, build times, and waiting for a state change
  mutable std::condition_variable settled_;
  Status failure_;
  std::string message_;
  BuildTimes build_times_;
  std::string cache_key_;
};

}  // namespace robodiff::server::detail
