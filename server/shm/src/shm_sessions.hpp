#pragma once
// The iceoryx server's ports: the shared port ("robodiff", service, "rpc"), which only
// opens sessions, and one session per client connection ("robodiff", service,
// "rpc.<n>.<random>") with its own request queue, so a client flooding its queue fills
// only its own (docs/limits.md, "Fair sharing"). Every port is attached to the receive
// thread's WaitSet while it is not paused.
//
// Threading: the table (open, pause, resume, sweep, closeAll) belongs to the receive
// thread. A session's port is used by any thread under the session's mutex; a closed
// session's port is null (late replies are dropped), and the session itself lives on as
// long as a request of it does.

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "iceoryx_posh/popo/untyped_server.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "robodiff/server/service_api.hpp"
#include "robodiff/server/shm_server.hpp"  // ShmSessionLimits

namespace robodiff::server::shm_detail {

struct ShmSession {
  using Clock = std::chrono::steady_clock;
  std::uint64_t key = 0;           // the fair lane's key; 0: the shared port
  std::string event;               // iceoryx event: "rpc" for the shared port
  std::string client_id;           // at open
  Caller caller;                   // fixed at open (shm_caller.hpp)
  std::mutex mutex;                // the port is not thread-safe
  std::unique_ptr<iox::popo::UntypedServer> port;  // null once closed
  Clock::time_point opened{};
  Clock::time_point paused_until{};  // not drained before (its error budget is spent)
  bool attached = false;           // to the WaitSet
  bool had_client = false;         // a client connected (or sent) once: its leaving closes the session
  bool shared() const { return key == 0; }
};
using SessionPtr = std::shared_ptr<ShmSession>;

class ShmSessions {
 public:
  using Clock = ShmSession::Clock;
  ShmSessions(std::string service, ShmSessionLimits limits, iox::popo::WaitSet<>& waitset);

  // The shared port, first in all(). False when it cannot be attached.
  bool openShared(std::uint64_t queue_capacity);
  // A new session for `client_id`; RESOURCE_EXHAUSTED naming limits.max_shm_sessions at the cap.
  Status open(const std::string& client_id, Caller caller, SessionPtr& session);
  // The shared port, then the sessions in the order they opened.
  const std::vector<SessionPtr>& all() const { return sessions_; }
  std::size_t openSessions() const { return sessions_.empty() ? 0 : sessions_.size() - 1; }
  const ShmSessionLimits& limits() const { return limits_; }

  // Not drained until `until`: detached from the WaitSet (its queue fills, its senders wait).
  void pause(ShmSession& session, Clock::time_point until);
  // Re-attaches the sessions whose pause is over; returns the next time anything is due.
  Clock::time_point resumeDue(Clock::time_point now);
  // Closes sessions whose client went away (or never came within connect_grace).
  // Returns how many were closed.
  std::size_t sweep(Clock::time_point now);
  void closeAll();

 private:
  void attach(ShmSession& session);
  void detach(ShmSession& session);
  void close(ShmSession& session);
  std::string newEvent(std::uint64_t key);

  std::string service_;
  ShmSessionLimits limits_;
  iox::popo::WaitSet<>& waitset_;
  std::vector<SessionPtr> sessions_;
  std::uint64_t next_key_ = 1;
  std::mt19937_64 random_{std::random_device{}()};
};

}  // namespace robodiff::server::shm_detail
