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
#include "model_entry.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/schema/messages.hpp"
#include "robodiff/server/service_api.hpp"

namespace robodiff::server::detail {

class FunctionEntry {
 public:
  FunctionEntry(std::string id, std::shared_ptr<const ModelEntry> model, FunctionSpec spec, std::string spec_text,
                std::uint64_t sequence);

  const std::string& id() const { return id_; }
  const ModelEntry& model() const { return *model_; }
  const std::shared_ptr<const ModelEntry>& modelEntry() const { return model_; }
  const FunctionSpec& spec() const { return spec_; }
  const std::string& specText() const { return spec_text_; }
  const char* functionName() const { return toString(spec_.function); }  // "rnea"
  std::uint64_t sequence() const { return sequence_; }                   // order of creation

  rpc::FunctionState state() const { return state_.load(std::memory_order_acquire); }
  // The evaluator serving it; null unless READY.
  std::shared_ptr<const Evaluator> evaluator() const { return evaluator_.load(std::memory_order_acquire); }
  bool compiled() const;

  // BUILDING -> READY. Ignored unless BUILDING.
  void ready(std::shared_ptr<const Evaluator> evaluator);
  // READY: the compiled library replaces the interpreter.
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

  // Released (no references left): builds not started yet are skipped.
  void markUnloaded() { unloaded_.store(true, std::memory_order_release); }
  bool unloaded() const { return unloaded_.load(std::memory_order_acquire); }

  // Guarded by the registry's mutex.
  std::uint32_t references = 0;

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

  mutable std::mutex mutex_;  // the failure, the message, and waiting for a state change
  mutable std::condition_variable settled_;
  Status failure_;
  std::string message_;
};

}  // namespace robodiff::server::detail
