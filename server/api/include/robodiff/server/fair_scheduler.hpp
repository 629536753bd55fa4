#pragma once
// Fair sharing of a transport's receive thread and of the request threads between
// clients (issue 19, item 5). A transport's receive thread drains its transport queue
// quickly into one lane per client (the key: the iceoryx client port, the DDS writer),
// then serves one request per client in turn (round robin), so one flooding client
// delays another by at most one of its own requests per turn.
//
// Per client at most `max_queued` requests are pending (queued in its lane, waiting for
// a request thread, or running there): the transport refuses more with RESOURCE_EXHAUSTED.
// At most `max_running` of a client's posted requests (those run on the service's request
// threads) are handed to the service at once; the others wait here, in the client's
// order, and the next one is handed over when one finishes. So a client sending many
// expensive requests never fills the service's shared queue.
//
// A request stops being pending when its reply is about to be sent (answered()), not when
// its task ends: a client that waits for each reply before sending the next is never
// refused, however late the server's thread gets to the end of the task.
//
// Threading: push(), next() and served() on the receive thread only; startPosted() on
// the receive thread; answered() and finishPosted() on any thread (a request thread).
// The per-client ledger is guarded by a mutex, the lanes are the receive thread's own.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <utility>

namespace robodiff::server {

// A queued request's place in its client's quota: taken when the transport admits it
// (admit(), after push() returned true), given back once, by answered() when its reply
// goes out, or by served() / finishPosted() when it never went out (dropped at stop, a
// closed session).
class QuotaSlot {
 public:
  void admit() { admitted_.store(true); }
  bool answered() const { return answered_.load(); }
  // True once, for an admitted request: the caller gives its place back.
  bool answer() { return admitted_.load() && !answered_.exchange(true); }

 private:
  std::atomic<bool> admitted_{false}, answered_{false};
};

struct FairLimits {
  std::uint32_t max_queued = 64;   // requests pending per client; more: RESOURCE_EXHAUSTED
  std::uint32_t max_running = 2;   // posted requests per client handed to the request threads at once
};

template <class Item>
class FairScheduler {
 public:
  using Key = std::uint64_t;
  explicit FairScheduler(FairLimits limits = {}) : limits_(limits) {}

  const FairLimits& limits() const { return limits_; }

  // The client's pending requests (queued, deferred or running).
  std::uint32_t pending(Key client) const {
    std::lock_guard lock(mutex_);
    const auto it = ledger_.find(client);
    return it == ledger_.end() ? 0 : it->second.pending;
  }
  // False when the client has max_queued requests pending: the caller refuses this one.
  bool push(Key client, Item item) {
    {
      std::lock_guard lock(mutex_);
      Ledger& l = ledger_[client];
      if (l.pending >= limits_.max_queued) return false;
      ++l.pending;
    }
    Lane& lane = lanes_[client];
    lane.items.push_back(std::move(item));
    if (!lane.in_rotation) {
      lane.in_rotation = true;
      rotation_.push_back(client);
    }
    ++queued_;
    return true;
  }

  struct Next {
    Key client = 0;
    Item item;
  };
  // The next request in turn: the head of the next client's lane.
  std::optional<Next> next() {
    while (!rotation_.empty()) {
      const Key client = rotation_.front();
      rotation_.pop_front();
      auto it = lanes_.find(client);
      if (it == lanes_.end()) continue;
      Lane& lane = it->second;
      lane.in_rotation = false;
      if (lane.items.empty()) continue;
      Next n{client, std::move(lane.items.front())};
      lane.items.pop_front();
      --queued_;
      if (!lane.items.empty()) {
        lane.in_rotation = true;
        rotation_.push_back(client);
      } else if (lanes_.size() > kKeptIdleLanes) {
        lanes_.erase(it);
      }
      return n;
    }
    return std::nullopt;
  }
  bool empty() const { return queued_ == 0; }
  // Clients with a request queued: one round of next().
  std::size_t waitingClients() const { return rotation_.size(); }
  std::size_t queued() const { return queued_; }

  // A request's reply is about to be sent: it no longer counts as pending (once per
  // request, however many replies or chunks it sends).
  void answered(Key client, QuotaSlot& slot) {
    if (!slot.answer()) return;
    std::lock_guard lock(mutex_);
    release(client, true);
  }

  // A request next() returned was done with on the receive thread (answered or not).
  void served(Key client, const QuotaSlot& slot) {
    std::lock_guard lock(mutex_);
    release(client, !slot.answered());
  }

  // A posted request next() returned: true when it may be handed to the service now
  // (it counts as running); false when the client already has max_running running: the
  // item is kept and finishPosted() returns it later.
  bool startPosted(Key client, Item& item) {
    std::lock_guard lock(mutex_);
    Ledger& l = ledger_[client];
    if (l.running < limits_.max_running) {
      ++l.running;
      return true;
    }
    l.deferred.push_back(std::move(item));
    return false;
  }
  // A posted request of `client` finished (answered, or dropped unanswered): the
  // client's next deferred request, which then counts as running, to be handed over.
  std::optional<Item> finishPosted(Key client, const QuotaSlot& slot) {
    std::lock_guard lock(mutex_);
    Ledger& l = ledger_[client];
    if (l.running > 0) --l.running;
    release(client, !slot.answered());
    const auto it = ledger_.find(client);
    if (it == ledger_.end() || it->second.deferred.empty()) return std::nullopt;
    Item item = std::move(it->second.deferred.front());
    it->second.deferred.pop_front();
    ++it->second.running;
    return item;
  }

 private:
  static constexpr std::size_t kKeptIdleLanes = 256;  // lanes of quiet clients kept for reuse

  struct Lane {
    std::deque<Item> items;
    bool in_rotation = false;
  };
  struct Ledger {
    std::uint32_t pending = 0;  // queued + deferred + running
    std::uint32_t running = 0;  // posted, handed to the service
    std::deque<Item> deferred;  // posted, waiting for one of the client's running ones
  };

  // With mutex_ held: one pending request less (if `one_less`); the entry goes when the
  // client has none.
  void release(Key client, bool one_less) {
    const auto it = ledger_.find(client);
    if (it == ledger_.end()) return;
    if (one_less && it->second.pending > 0) --it->second.pending;
    if (it->second.pending == 0 && it->second.running == 0 && it->second.deferred.empty() &&
        ledger_.size() > kKeptIdleLanes)
      ledger_.erase(it);
  }

  FairLimits limits_;
  std::unordered_map<Key, Lane> lanes_;
  std::deque<Key> rotation_;  // clients with queued requests, in turn order
  std::size_t queued_ = 0;
  mutable std::mutex mutex_;
  std::unordered_map<Key, Ledger> ledger_;
};

}  // namespace robodiff::server
