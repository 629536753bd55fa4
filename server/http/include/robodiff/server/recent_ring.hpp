#pragma once
// A bounded ring of the latest values: once full, push() overwrites the oldest, so it
// never holds more than its capacity; snapshot() copies them oldest first. One mutex
// makes it safe for any number of writers and readers at once (the dashboard's history
// pushes once a second and is read on a page load: nothing contends).

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <utility>
#include <vector>

namespace robodiff::server {

template <class T>
class RecentRing {
 public:
  // Throws std::invalid_argument for a capacity of 0.
  explicit RecentRing(std::size_t capacity) : capacity_(capacity) {
    if (capacity == 0) throw std::invalid_argument("RecentRing: the capacity must be at least 1");
    slots_.reserve(capacity);
  }

  void push(T value) {
    std::lock_guard lock(mutex_);
    if (slots_.size() < capacity_) {
      slots_.push_back(std::move(value));
    } else {
      slots_[oldest_] = std::move(value);
      oldest_ = (oldest_ + 1) % capacity_;
    }
    ++pushed_;
  }

  // The values held, oldest first.
  std::vector<T> snapshot() const {
    return snapshotIf([](const T&) { return true; });
  }

  // The values held for which keep(value) is true, oldest first.
  template <class Keep>
  std::vector<T> snapshotIf(Keep keep) const {
    std::lock_guard lock(mutex_);
    std::vector<T> out;
    out.reserve(slots_.size());
    for (std::size_t i = 0; i < slots_.size(); ++i) {
      const T& value = slots_[(oldest_ + i) % slots_.size()];
      if (keep(value)) out.push_back(value);
    }
    return out;
  }

  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return slots_.size();
  }
  std::size_t capacity() const { return capacity_; }
  // Values ever pushed (those beyond the capacity were overwritten).
  std::uint64_t pushed() const {
    std::lock_guard lock(mutex_);
    return pushed_;
  }

 private:
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::vector<T> slots_;     // grows to capacity_, then is overwritten in a circle
  std::size_t oldest_ = 0;   // once full: the slot of the oldest value (the next to go)
  std::uint64_t pushed_ = 0;
};

}  // namespace robodiff::server
