#pragma once
// The calls of one connection waiting for their replies, by correlation id. The receive
// thread hands each reply to its call; the caller waits on its own condition variable.
// Replies are consumed under the table's lock, so a caller that gives up (timeout) can never
// have its reply object or output span written after it returned; a reply that finds no
// call (late, or not ours) is dropped.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "robodiff.h"
#include "robodiff/schema/messages.hpp"

namespace robodiff::client::dds_detail {

using Clock = std::chrono::steady_clock;

struct PendingCall {
  rpc::Method method = rpc::Method::Health;
  // Reads one OK reply sample of this call into the caller's reply / outputs; sets
  // `complete` (false only while chunks of a batch are missing). A non-OK result ends the call.
  std::function<Status(const robodiff_wire_Reply& reply, bool& complete)> consume;

  bool done = false;  // guarded by the table's mutex
  Status status;
  std::condition_variable cv;
};

class PendingCalls {
 public:
  PendingCalls() { calls_.reserve(64); }  // no allocation per call until 64 are pending at once

  // Registers a call; false while closed (no server matched): send nothing then.
  bool add(std::uint64_t id, PendingCall& call);
  void remove(std::uint64_t id);
  // Waits for the call's reply until `deadline`; the call is removed either way. nullopt:
  // the deadline passed first.
  std::optional<Status> wait(std::uint64_t id, PendingCall& call, Clock::time_point deadline);
  // The receive thread: gives the reply to the call with its correlation id, if any.
  void deliver(const robodiff_wire_Reply& reply);

  // A server is matched: calls may be added.
  void open();
  // The server went away: every pending call ends with `code` and `message` plus the method
  // it waited for; new calls are refused until open().
  void close(StatusCode code, const std::string& message);
  std::size_t size() const;

 private:
  using Entry = std::pair<std::uint64_t, PendingCall*>;
  std::vector<Entry>::iterator find(std::uint64_t id);
  void erase(std::vector<Entry>::iterator it);  // swaps with the last entry
  void finish(std::vector<Entry>::iterator it, Status status);

  mutable std::mutex mutex_;
  bool open_ = false;
  // Unordered (correlation id, call): a few calls pending at a time, so a linear search
  // beats hashing, and the reserved vector never allocates per call as map nodes would.
  std::vector<Entry> calls_;
};

}  // namespace robodiff::client::dds_detail
