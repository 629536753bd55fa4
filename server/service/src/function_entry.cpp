#include "function_entry.hpp"

namespace robodiff::server::detail {

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
  evaluator_.store(std::move(evaluator), std::memory_order_release);
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

}  // namespace robodiff::server::detail
