// Choosing how to reach robodiff: the local cache (Local), iceoryx (Shm) or DDS (Dds).
#include <system_error>
#include <thread>

#include "client_impl.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/shm_connection.hpp"

namespace robodiff::client {
namespace {

using std::chrono::milliseconds;

void note(std::string& tried, const std::string& what) {
  if (!tried.empty()) tried += "; ";
  tried += what;
}

// Opens the cache if its directory exists (never creates one); notes why not.
void openCache(Client::Impl& c) {
  const std::filesystem::path dir = c.options.cache_dir.empty() ? cache::defaultCacheDir() : c.options.cache_dir;
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    note(c.tried, "local cache " + dir.string() + ": no such directory");
    return;
  }
  try {
    cache::CacheOptions options;
    options.create = false;
    c.cache.emplace(cache::Cache::open(dir, options));
  } catch (const std::exception& e) {
    note(c.tried, "local cache " + dir.string() + ": " + e.what());
  }
}

// iceoryx: nullptr (noted) without a RouDi, or without a server when require_server.
bool connectShmTo(Client::Impl& c, bool require_server, milliseconds wait) {
  ShmConnectionOptions options;
  options.client_id = c.options.client_id;
  options.default_timeout = c.options.timeout;
  options.service = c.options.server.shm_service;
  options.connect_timeout = wait;
  options.require_server = require_server;
  Status status;
  std::unique_ptr<ShmConnection> shm = connectShm(options, status);
  const std::string what = "shm (iceoryx service " + options.service + ")";
  if (shm == nullptr) {
    note(c.tried, what + ": " + toString(status.code) + ": " + status.message);
    return false;
  }
  if (!shm->serverConnected()) {
    note(c.tried, what + ": no server offers the service");
    return false;
  }
  c.shm = shm.get();
  c.connection = std::move(shm);
  c.remote = Mode::Shm;
  return true;
}

// DDS: the connection is kept (calls answer UNAVAILABLE until a server is discovered)
// unless require_server; waits up to `wait` for a server.
bool connectDdsTo(Client::Impl& c, bool require_server, milliseconds wait) {
  DdsConnectionOptions options;
  options.connection.client_id = c.options.client_id;
  options.connection.default_timeout = c.options.timeout;
  if (c.options.server.dds_domain >= 0) options.domain_id = static_cast<std::uint32_t>(c.options.server.dds_domain);
  const std::string what = "dds (domain " +
                           (c.options.server.dds_domain >= 0 ? std::to_string(c.options.server.dds_domain)
                                                             : std::string("default")) +
                           ")";
  std::unique_ptr<DdsConnection> dds;
  try {
    dds = std::make_unique<DdsConnection>(options);
  } catch (const std::exception& e) {
    note(c.tried, what + ": " + e.what());
    return false;
  }
  const auto until = std::chrono::steady_clock::now() + wait;
  while (!dds->connected() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(milliseconds(10));
  if (!dds->connected()) {
    note(c.tried, what + ": no server discovered within " + std::to_string(wait.count()) + " ms");
    if (require_server) return false;
  }
  c.dds = dds.get();
  c.connection = std::move(dds);
  c.remote = Mode::Dds;
  return true;
}

milliseconds capped(std::chrono::nanoseconds timeout, milliseconds cap) {
  const auto t = std::chrono::duration_cast<milliseconds>(timeout);
  return t.count() > 0 && t < cap ? t : cap;
}

}  // namespace

std::shared_ptr<Client::Impl> connectClient(ClientOptions options) {
  auto c = std::make_shared<Client::Impl>();
  c->options = std::move(options);
  if (c->options.client_id.empty()) c->options.client_id = defaultClientId();
  c->requested = c->options.server.mode;
  switch (c->requested) {
    case Mode::Shm:
      if (!connectShmTo(*c, true, capped(c->options.timeout, milliseconds(3000))))
        throw ClientError({StatusCode::Unavailable, "mode shm: no robodiffd reachable: tried " + c->tried});
      break;
    case Mode::Dds:
      if (!connectDdsTo(*c, true, capped(c->options.timeout, milliseconds(3000))))
        throw ClientError({StatusCode::Unavailable, "mode dds: no robodiffd reachable: tried " + c->tried});
      break;
    case Mode::Local:
    case Mode::Auto:
      openCache(*c);
      if (c->requested == Mode::Local && !c->cache)
        throw ClientError({StatusCode::Unavailable,
                           "mode local: the cache cannot be used: tried " + c->tried +
                               " (run `robodiff warmup` or start robodiffd to fill it, or give another cache_dir)"});
      // A server, when there is one, loads models and builds functions (Local too).
      if (!connectShmTo(*c, false, milliseconds(300))) connectDdsTo(*c, false, milliseconds(1000));
      break;
  }
  return c;
}

bool Client::Impl::serverPresent() const {
  if (shm != nullptr) return shm->serverConnected();
  if (dds != nullptr) return dds->connected();
  return false;
}

Status Client::Impl::noServer() const {
  return {StatusCode::Unavailable, std::string("no robodiffd answers (mode ") + client::toString(requested) +
                                       "; tried " + tried + ")"};
}

}  // namespace robodiff::client
