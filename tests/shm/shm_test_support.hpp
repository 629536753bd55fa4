// What the iceoryx transport tests share: a server with a FakeService on the shared RouDi,
// connections to it, and running this test binary again as a child process (a fresh
// process: iceoryx allows one runtime per process).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "fake_service.hpp"
#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iceoryx_posh/popo/untyped_client.hpp"
#include "robodiff/schema/shm_codec.hpp"
#include "robodiff/client/shm_connection.hpp"
#include "robodiff/server/shm_server.hpp"
#include "roudi_fixture.hpp"

namespace robodiff::testing {

// Set in a child started by startChild(); the child-only tests skip without it.
inline const char* childMode() { return std::getenv("ROBODIFF_SHM_TEST_CHILD"); }

// Runs this binary with --gtest_filter=<test> and ROBODIFF_SHM_TEST_CHILD=<mode>.
inline pid_t startChild(const std::string& test, const std::string& mode) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("ROBODIFF_SHM_TEST_CHILD", mode.c_str(), 1);
    const std::string filter = "--gtest_filter=" + test;
    ::execl("/proc/self/exe", "shm_tests", filter.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

inline int waitChild(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

inline bool waitUntil(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

inline server::Logger& quietLog() {
  static server::Logger log(stderr, server::LogLevel::Warn, server::LogFormat::Text);
  return log;
}

inline std::unique_ptr<client::ShmConnection> connect(std::string service,
                                                      std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  client::ShmConnectionOptions options;
  options.service = std::move(service);
  options.default_timeout = timeout;
  options.connect_timeout = std::chrono::seconds(3);
  Status status;
  auto c = client::connectShm(options, status);
  EXPECT_TRUE(status.ok()) << toString(status.code) << ": " << status.message;
  return c;
}

// A raw iceoryx client port on ("robodiff", service, event), as robodiffd connects them
// (waiting while the server's queue is full).
inline std::unique_ptr<iox::popo::UntypedClient> rawClient(const std::string& service, const std::string& event) {
  iox::popo::ClientOptions waits;
  waits.serverTooSlowPolicy = iox::popo::ConsumerTooSlowPolicy::WAIT_FOR_CONSUMER;
  auto raw = std::make_unique<iox::popo::UntypedClient>(
      iox::capro::ServiceDescription("robodiff", iox::capro::IdString_t(iox::cxx::TruncateToCapacity, service.c_str()),
                                     iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event.c_str())),
      waits);
  waitUntil([&] { return raw->getConnectionState() == iox::ConnectionState::CONNECTED; }, std::chrono::seconds(3));
  return raw;
}

// Sends `fill`'s chunk of `size` bytes on `raw` and returns the reply's status (its body
// into `body`), or INTERNAL when none comes within 3 s.
template <class Fill>
Status rawExchange(iox::popo::UntypedClient& raw, std::uint32_t size, Fill&& fill, std::string* body = nullptr,
                   bool session_reply = false) {
  auto loaned = raw.loan(size, 8);
  if (loaned.has_error()) return {StatusCode::Internal, "loan failed"};
  std::memset(loaned.value(), 0, size);
  fill(static_cast<std::byte*>(loaned.value()));
  if (raw.send(loaned.value()).has_error()) return {StatusCode::Internal, "send failed"};
  const void* response = nullptr;
  waitUntil([&] {
    auto taken = raw.take();
    if (!taken.has_error()) response = taken.value();
    return response != nullptr;
  }, std::chrono::seconds(3));
  if (response == nullptr) return {StatusCode::Internal, "no reply"};
  shm::ReplyView view;
  const auto bytes = iox::mepoo::ChunkHeader::fromUserPayload(response)->userPayloadSize();
  Status s = session_reply ? shm::parseSessionReply(response, bytes, view) : shm::parseReply(response, bytes, view);
  if (s.ok() && body) body->assign(reinterpret_cast<const char*>(view.body.data()), view.body.size());
  raw.releaseResponse(response);
  return s.ok() ? view.header.status : s;
}

// Opens a session by hand on the shared port; its event ("rpc.<n>.<random>") or "".
inline std::string openRawSession(const std::string& service, Status* status = nullptr) {
  auto hello = rawClient(service, "rpc");
  std::string event;
  const Status s = rawExchange(
      *hello, static_cast<std::uint32_t>(shm::chunkSize(0, 0)),
      [](std::byte* chunk) {
        rpc::RequestHeader h;
        h.client_id = "raw-session";
        shm::writeSessionOpen(chunk, h);
      },
      &event, /*session_reply=*/true);
  if (status) *status = s;
  return s.ok() ? event : "";
}

}  // namespace robodiff::testing
