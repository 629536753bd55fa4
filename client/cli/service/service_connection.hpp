// What the service commands (load, eval, functions, health, warmup --server) share:
// --server ADDR and --timeout SECONDS, connecting to robodiffd over iceoryx or DDS, and
// the errors main turns into exit statuses:
//   0 OK; 1 the server answered an error (ServiceError; "robodiff: CODE: message" on
//   stderr); 2 bad usage (UsageError, or a command line CLI11 refuses); 3 no server
//   reachable (ServiceError with UNAVAILABLE).
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>

#include "robodiff/client/connection.hpp"
#include "robodiff/schema/status.hpp"

namespace robodiff::cli {

inline constexpr int kExitServerError = 1;
inline constexpr int kExitUsage = 2;
inline constexpr int kExitUnavailable = 3;

// A non-OK status from the server, or made here (UNAVAILABLE: no server answered).
class ServiceError : public std::runtime_error {
 public:
  explicit ServiceError(Status status);
  const Status& status() const { return status_; }
  int exitCode() const;  // 3 for UNAVAILABLE, else 1

 private:
  Status status_;
};

// A command line that cannot be used (exit status 2).
class UsageError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Throws ServiceError naming `what` (the method) unless `status` is OK.
void check(const Status& status, const std::string& what);
// "NOT_FOUND: no function ...": a status as one line of text.
std::string describe(const Status& status);

struct ServiceArgs {
  std::string server;            // empty: $ROBODIFF_SERVER, else auto
  double timeout_seconds = 30;   // per call (and how long to look for a server)
};

// The footer every service command's --help ends with: the exit statuses.
extern const char* const kServiceExitHelp;

// --server ADDR and --timeout SECONDS. `server_help` replaces the default help of --server.
CLI::Option* addServiceOptions(CLI::App& cmd, ServiceArgs& args, const std::string& server_help = "");
// Checks a --server value (CLI11 validator): auto, shm, shm:<service>, dds, dds:<domain>.
CLI::Validator serverAddressValidator();

struct ServiceConnection {
  std::unique_ptr<client::Connection> connection;
  std::string transport;  // "iceoryx" or "dds"
  std::string address;    // "shm:<service>" or "dds:<domain>"
  std::chrono::nanoseconds timeout{0};

  client::Connection* operator->() const { return connection.get(); }
  client::CallOptions call() const { return client::CallOptions{timeout}; }
};

// Connects per args.server: shm (a RouDi and a server offering the service must answer),
// dds (the first call waits for a server), auto (shm when a RouDi and a server answer,
// else dds, waiting until a server is discovered). Throws UsageError for a bad address,
// ServiceError UNAVAILABLE naming what was tried when no server answers.
ServiceConnection connectService(const ServiceArgs& args);

}  // namespace robodiff::cli
