// The iceoryx server's shared port and per-connection sessions (shm_sessions.hpp).
#include "shm_sessions.hpp"

#include "robodiff/server/shm_caller.hpp"

#include <algorithm>
#include <cstdio>

namespace robodiff::server::shm_detail {
namespace {

iox::popo::ServerOptions serverOptions(std::uint64_t queue_capacity) {
  iox::popo::ServerOptions options;
  options.requestQueueCapacity = std::clamp<std::uint64_t>(queue_capacity, 1, iox::MAX_REQUEST_QUEUE_CAPACITY);
  // A full queue makes its sender wait instead of dropping its oldest request; iceoryx
  // connects only clients that agree to wait (ConsumerTooSlowPolicy::WAIT_FOR_CONSUMER).
  options.requestQueueFullPolicy = iox::popo::QueueFullPolicy::BLOCK_PRODUCER;
  return options;
}

}  // namespace

ShmSessions::ShmSessions(std::string service, ShmSessionLimits limits, iox::popo::WaitSet<>& waitset)
    : service_(std::move(service)), limits_(limits), waitset_(waitset) {}

bool ShmSessions::openShared(std::uint64_t queue_capacity) {
  auto shared = std::make_shared<ShmSession>();
  shared->event = "rpc";
  shared->opened = Clock::now();
  shared->port = std::make_unique<iox::popo::UntypedServer>(
      iox::capro::ServiceDescription("robodiff", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, service_.c_str()),
                                     "rpc"),
      serverOptions(queue_capacity));
  attach(*shared);
  if (!shared->attached) return false;
  sessions_.insert(sessions_.begin(), std::move(shared));
  return true;
}

std::string ShmSessions::newEvent(std::uint64_t key) {
  char random[17];
  std::snprintf(random, sizeof random, "%016llx", static_cast<unsigned long long>(random_()));
  return "rpc." + std::to_string(key) + "." + random;  // < 45 characters, within IdString_t
}

Status ShmSessions::open(const std::string& client_id, Caller caller, SessionPtr& session) {
  if (openSessions() >= limits_.max_sessions)
    return {StatusCode::ResourceExhausted,
            "robodiffd has " + std::to_string(openSessions()) +
                " iceoryx sessions open, the most it serves at once (limits.max_shm_sessions = " +
                std::to_string(limits_.max_sessions) + "); close another connection or use DDS"};
  session = std::make_shared<ShmSession>();
  session->key = next_key_++;
  session->event = newEvent(session->key);
  session->client_id = client_id;
  session->caller = std::move(caller);
  session->opened = Clock::now();
  session->port = std::make_unique<iox::popo::UntypedServer>(
      iox::capro::ServiceDescription("robodiff", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, service_.c_str()),
                                     iox::capro::IdString_t(iox::cxx::TruncateToCapacity, session->event.c_str())),
      serverOptions(limits_.queue_capacity));
  attach(*session);
  if (!session->attached) {
    session->port.reset();
    return {StatusCode::ResourceExhausted, "the iceoryx WaitSet of robodiffd is full; lower limits.max_shm_sessions"};
  }
  sessions_.push_back(session);
  return {};
}

void ShmSessions::attach(ShmSession& session) {
  if (session.attached || !session.port) return;
  session.attached = !waitset_.attachState(*session.port, iox::popo::ServerState::HAS_REQUEST).has_error();
}

void ShmSessions::detach(ShmSession& session) {
  if (!session.attached) return;
  waitset_.detachState(*session.port, iox::popo::ServerState::HAS_REQUEST);
  session.attached = false;
}

void ShmSessions::pause(ShmSession& session, Clock::time_point until) {
  session.paused_until = until;
  detach(session);
}

ShmSessions::Clock::time_point ShmSessions::resumeDue(Clock::time_point now) {
  auto next = Clock::time_point::max();
  for (auto& s : sessions_) {
    if (s->attached || !s->port) continue;
    if (s->paused_until <= now) attach(*s);
    else next = std::min(next, s->paused_until);
  }
  return next;
}

void ShmSessions::close(ShmSession& session) {
  detach(session);
  std::lock_guard lock(session.mutex);
  session.port.reset();  // RouDi stops offering its service; requests still queued go with it
}

std::size_t ShmSessions::sweep(Clock::time_point now) {
  std::size_t closed = 0;
  for (auto it = sessions_.begin(); it != sessions_.end();) {
    ShmSession& s = **it;
    bool gone = false;
    if (!s.shared()) {
      std::lock_guard lock(s.mutex);
      if (s.port->hasClients()) s.had_client = true;
      else gone = s.had_client || now - s.opened > limits_.connect_grace;
      // A killed client never disconnects its port: its process is gone.
      gone = gone || shmClientProcessGone(s.client_id);
    }
    if (!gone) {
      ++it;
      continue;
    }
    close(s);
    it = sessions_.erase(it);
    ++closed;
  }
  return closed;
}

void ShmSessions::closeAll() {
  for (auto& s : sessions_) close(*s);
  sessions_.clear();
}

}  // namespace robodiff::server::shm_detail
