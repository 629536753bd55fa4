// The pending-call table of a DDS connection: correlation id -> waiting caller.
#include "pending_calls.hpp"

#include <algorithm>

#include "robodiff/schema/dds_codec.hpp"

namespace robodiff::client::dds_detail {

std::vector<PendingCalls::Entry>::iterator PendingCalls::find(std::uint64_t id) {
  return std::find_if(calls_.begin(), calls_.end(), [id](const Entry& e) { return e.first == id; });
}

void PendingCalls::erase(std::vector<Entry>::iterator it) {
  if (it == calls_.end()) return;
  *it = calls_.back();
  calls_.pop_back();
}

bool PendingCalls::add(std::uint64_t id, PendingCall& call) {
  std::lock_guard lock(mutex_);
  if (!open_) return false;
  call.done = false;
  if (const auto it = find(id); it != calls_.end())
    it->second = &call;
  else
    calls_.emplace_back(id, &call);
  return true;
}

void PendingCalls::remove(std::uint64_t id) {
  std::lock_guard lock(mutex_);
  erase(find(id));
}

std::optional<Status> PendingCalls::wait(std::uint64_t id, PendingCall& call, Clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  const bool done = call.cv.wait_until(lock, deadline, [&] { return call.done; });
  if (!done) {
    erase(find(id));  // a reply arriving later finds nothing and is dropped
    return std::nullopt;
  }
  return call.status;
}

void PendingCalls::finish(std::vector<Entry>::iterator it, Status status) {
  PendingCall& call = *it->second;
  erase(it);
  call.status = std::move(status);
  call.done = true;
  call.cv.notify_one();
}

void PendingCalls::deliver(const robodiff_wire_Reply& reply) {
  std::lock_guard lock(mutex_);
  const auto it = find(reply.header.correlation_id);
  if (it == calls_.end()) return;
  PendingCall& call = *it->second;
  const auto method = dds_codec::methodFromWire(reply.body._d);
  if (!method || *method != call.method)
    return finish(it, {StatusCode::Internal,
                       std::string("robodiffd answered a ") + rpc::toString(call.method) + " request with a " +
                           (method ? rpc::toString(*method) : "unknown-method") + " reply"});
  const StatusCode code = dds_codec::statusFromWire(reply.header.status.code);
  if (code != StatusCode::Ok) return finish(it, {code, dds_codec::toString(reply.header.status.message)});
  bool complete = true;
  Status status = call.consume(reply, complete);
  if (!status.ok() || complete) finish(it, std::move(status));
}

void PendingCalls::open() {
  std::lock_guard lock(mutex_);
  open_ = true;
}

void PendingCalls::close(StatusCode code, const std::string& message) {
  std::lock_guard lock(mutex_);
  open_ = false;
  while (!calls_.empty()) {
    const auto it = calls_.end() - 1;
    finish(it, {code, message + " (waiting for the reply to " + rpc::toString(it->second->method) + ")"});
  }
}

std::size_t PendingCalls::size() const {
  std::lock_guard lock(mutex_);
  return calls_.size();
}

}  // namespace robodiff::client::dds_detail
