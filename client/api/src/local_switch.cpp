// Switching a Function to Local evaluation once its library is in the cache: looked at
// when the Function is made, then from calling threads at most every 100 ms (one thread
// at a time; the others do not wait) until it is there.
#include "client_impl.hpp"

namespace robodiff::client {
namespace {

std::int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

constexpr std::int64_t kCheckEveryNs = 100'000'000;

}  // namespace

bool Function::Impl::tryLoadLocal(std::string* problem) {
  if (local.load(std::memory_order_acquire) != nullptr) return true;
  Client::Impl& c = *client;
  if (!c.cache || (key.empty() && portable_keys.empty())) return false;
  std::optional<cache::Artifact> artifact;
  try {
    std::lock_guard lock(c.cache_mutex);
    if (!key.empty()) artifact = c.cache->find(key);  // verifies the SHA-256; a mismatch is quarantined: a miss
    // Built elsewhere (imported), by another compiler than this host's, or none here.
    for (const std::string& portable : portable_keys)
      if (!artifact) artifact = c.cache->findPortable(portable);
  } catch (const std::exception& e) {
    if (problem != nullptr) *problem = std::string("the cache: ") + e.what();
    return false;
  }
  if (!artifact) return false;
  try {
    auto evaluator = std::make_unique<detail::LocalEvaluator>(std::move(*artifact), spec);
    if (!layout.function_id.empty()) {
      const std::string difference = evaluator->differenceFrom(layout);
      if (!difference.empty()) {
        if (problem != nullptr)
          *problem = "the cached library's layout differs from the server's: " + difference;
        local_candidate = false;
        return false;
      }
    }
    local_owner = std::move(evaluator);
    local.store(local_owner.get(), std::memory_order_release);
    local_candidate = false;
    return true;
  } catch (const std::exception& e) {
    if (problem != nullptr) *problem = e.what();
    local_candidate = false;
    return false;
  }
}

void Function::Impl::maybeSwitchToLocal() {
  const std::int64_t now = nowNs();
  if (now < next_check_ns.load(std::memory_order_relaxed)) return;
  std::unique_lock lock(switch_mutex, std::try_to_lock);
  if (!lock.owns_lock() || !local_candidate) return;
  next_check_ns.store(now + kCheckEveryNs, std::memory_order_relaxed);
  tryLoadLocal();
}

}  // namespace robodiff::client
