#pragma once
// What a client's bad requests may cost (issue 19, item 5): malformed requests, or
// requests over the client's queue quota, get at most `replies_per_second` error replies
// per client per second; the rest are dropped without a reply (and the iceoryx
// transport stops taking the client's requests until window_end). The log gets at most one
// line per client per second, with the count since the last one. A transport's receive
// thread owns its budgets (no lock).

#include <chrono>
#include <cstdint>
#include <unordered_map>

namespace robodiff::server {

class ErrorBudget {
 public:
  using Key = std::uint64_t;
  using Clock = std::chrono::steady_clock;

  explicit ErrorBudget(std::uint32_t replies_per_second = 100) : replies_per_second_(replies_per_second) {}

  struct Decision {
    bool reply = false;          // answer this one with its error; else drop it silently
    bool log = false;            // log one summary line now, with the counts below
    std::uint64_t count = 0;     // bad requests of this client since its last log line
    std::uint64_t dropped = 0;   // of those, dropped without a reply
    Clock::time_point window_end{};  // when the client's budget is refilled
  };

  // Counts one bad request of `client`.
  Decision note(Key client, Clock::time_point now = Clock::now()) {
    if (clients_.size() > kMaxClients) clients_.clear();  // a flood of new ports: start over
    Entry& e = clients_[client];
    if (now - e.window_start >= std::chrono::seconds(1)) {
      e.window_start = now;
      e.replies = 0;
    }
    Decision d;
    d.window_end = e.window_start + std::chrono::seconds(1);
    d.reply = e.replies < replies_per_second_;
    if (d.reply) ++e.replies;
    else ++e.dropped;
    ++e.count;
    if (now - e.last_log >= std::chrono::seconds(1)) {  // the first one at once
      d.log = true;
      d.count = e.count;
      d.dropped = e.dropped;
      e.count = e.dropped = 0;
      e.last_log = now;
    }
    return d;
  }

 private:
  static constexpr std::size_t kMaxClients = 4096;
  struct Entry {
    Clock::time_point window_start{}, last_log{};
    std::uint32_t replies = 0;
    std::uint64_t count = 0, dropped = 0;
  };
  std::uint32_t replies_per_second_;
  std::unordered_map<Key, Entry> clients_;
};

}  // namespace robodiff::server
