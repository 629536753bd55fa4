#include "service/service_connection.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

#include "robodiff/client/client.hpp"
#include "robodiff/client/dds_connection.hpp"
#include "robodiff/client/shm_connection.hpp"
#include "robodiff/schema/shm_runtime.hpp"

namespace robodiff::cli {

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

std::string secondsText(milliseconds d) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", static_cast<double>(d.count()) / 1000.0);
  return buf;
}

client::ServerAddress resolveAddress(const ServiceArgs& args) {
  try {
    if (!args.server.empty()) return client::parseServerAddress(args.server);
    return client::serverAddressFromEnvironment();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--server: ") + e.what());
  }
}

std::string ddsAddress(const client::ServerAddress& a) {
  return a.dds_domain >= 0 ? "dds:" + std::to_string(a.dds_domain) : std::string("dds");
}

// A shared-memory connection to the service, or nullptr with `status` saying why.
std::unique_ptr<client::ShmConnection> tryShm(const client::ServerAddress& a, std::chrono::nanoseconds timeout,
                                              milliseconds connect_timeout, Status& status) {
  if (!shm::roudiRunning()) {
    status = {StatusCode::Unavailable, "no iceoryx RouDi is running on this host"};
    return nullptr;
  }
  client::ShmConnectionOptions options;
  options.service = a.shm_service;
  options.default_timeout = timeout;
  options.connect_timeout = connect_timeout;
  options.require_server = true;
  return client::connectShm(options, status);
}

std::unique_ptr<client::DdsConnection> makeDds(const client::ServerAddress& a, std::chrono::nanoseconds timeout,
                                               milliseconds match_timeout) {
  client::DdsConnectionOptions options;
  options.connection.default_timeout = timeout;
  if (a.dds_domain >= 0) options.domain_id = static_cast<std::uint32_t>(a.dds_domain);
  options.match_timeout = match_timeout;
  try {
    return std::make_unique<client::DdsConnection>(options);
  } catch (const std::exception& e) {
    throw ServiceError({StatusCode::Unavailable, std::string("DDS: ") + e.what()});
  }
}

}  // namespace

std::string describe(const Status& status) { return toString(status.code) + ": " + status.message; }

ServiceError::ServiceError(Status status) : std::runtime_error(describe(status)), status_(std::move(status)) {}

int ServiceError::exitCode() const {
  return status_.code == StatusCode::Unavailable ? kExitUnavailable : kExitServerError;
}

void check(const Status& status, const std::string& what) {
  if (status.ok()) return;
  Status named = status;
  if (named.message.empty()) named.message = what + " failed";
  throw ServiceError(std::move(named));
}

const char* const kServiceExitHelp =
    "Exit status: 0 OK; 1 the server answered an error (its status and message on stderr, e.g. "
    "\"robodiff: INVALID_ARGUMENT: ...\"), or a local file could not be used; 2 bad usage; 3 no server reachable "
    "(UNAVAILABLE).";

CLI::Validator serverAddressValidator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        try {
          const client::ServerAddress a = client::parseServerAddress(text);
          if (a.mode == client::Mode::Local)
            return "'local' is not a server: use auto, shm, shm:<service>, dds or dds:<domain>";
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
        return {};
      },
      "");
}

CLI::Option* addServiceOptions(CLI::App& cmd, ServiceArgs& args, const std::string& server_help) {
  CLI::Option* server =
      cmd.add_option("--server", args.server,
                     server_help.empty()
                         ? "Where robodiffd is: auto (default: shared memory when a RouDi and a server answer, else "
                           "DDS), shm, shm:<service>, dds, dds:<domain>. Default: $ROBODIFF_SERVER, else auto"
                         : server_help)
          ->check(serverAddressValidator())
          ->type_name("ADDR");
  cmd.add_option("--timeout", args.timeout_seconds,
                 "Longest each call to the server may take, finding the server included (default 30)")
      ->check(CLI::PositiveNumber)
      ->type_name("SECONDS");
  return server;
}

ServiceConnection connectService(const ServiceArgs& args) {
  const client::ServerAddress a = resolveAddress(args);
  if (a.mode == client::Mode::Local)
    throw UsageError("--server local: the service commands need a server (auto, shm, shm:<service>, dds, dds:<domain>)");
  const auto timeout_ms = milliseconds(std::max<long long>(1, std::llround(args.timeout_seconds * 1000.0)));
  const std::chrono::nanoseconds timeout = timeout_ms;
  ServiceConnection c;
  c.timeout = timeout;

  if (a.mode == client::Mode::Shm) {
    Status status;
    std::unique_ptr<client::ShmConnection> shm = tryShm(a, timeout, std::min(timeout_ms, milliseconds(2000)), status);
    if (!shm) {
      if (status.code == StatusCode::Unavailable)
        status.message = "no robodiff server on shared memory (service '" + a.shm_service + "'): " + status.message;
      throw ServiceError(status);
    }
    c.connection = std::move(shm);
    c.transport = "iceoryx";
    c.address = "shm:" + a.shm_service;
    return c;
  }

  const milliseconds match_timeout = std::min(timeout_ms, milliseconds(3000));
  std::string shm_problem;
  if (a.mode == client::Mode::Auto) {
    Status status;
    std::unique_ptr<client::ShmConnection> shm = tryShm(a, timeout, std::min(timeout_ms, milliseconds(500)), status);
    if (shm) {
      c.connection = std::move(shm);
      c.transport = "iceoryx";
      c.address = "shm:" + a.shm_service;
      return c;
    }
    shm_problem = status.message;
  }

  std::unique_ptr<client::DdsConnection> dds = makeDds(a, timeout, match_timeout);
  c.address = ddsAddress(a);
  c.transport = "dds";
  if (a.mode == client::Mode::Auto) {
    // Auto insists on a server now, so that the message can say what was tried.
    const auto until = Clock::now() + match_timeout;
    while (!dds->connected() && Clock::now() < until) std::this_thread::sleep_for(milliseconds(10));
    if (!dds->connected())
      throw ServiceError({StatusCode::Unavailable, "no robodiff server answered: shared memory: " + shm_problem +
                                                       "; DDS (default domain): none found within " +
                                                       secondsText(match_timeout) + " (--server picks one)"});
  }
  c.connection = std::move(dds);
  return c;
}

}  // namespace robodiff::cli
