// robodiffd: the robodiff service daemon. Reads its configuration (embedded defaults, a
// file, flags), opens the cache, starts the build workers, serves over iceoryx (starting
// a RouDi inside the process when none runs) and Cyclone DDS, answers operators over HTTP
// (the dashboard at /, GET /metrics, /healthz, /readyz; 127.0.0.1:9464 by default), and on SIGTERM or SIGINT
// drains: new requests get UNAVAILABLE, requests in flight are answered, then it exits 0.
//
// Exit codes: 0 stopped cleanly; 1 could not start (the log says why); 2 bad usage or
// configuration; 3 drained too slowly (requests were still in flight at the drain timeout,
// or stopping outlasted it); 4 RouDi no longer knows it, after a pause (pause_monitor.hpp)
// or a RouDi restart (roudi_watch.hpp): its iceoryx ports are gone, so it drains the rest
// and exits for its supervisor to restart it.
#include <pthread.h>
#include <unistd.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include <nlohmann/json.hpp>

#include "robodiff/batch/batch_job.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/language/json_problem.hpp"
#include "robodiff/schema/shm_runtime.hpp"
#include "robodiff/server/dashboard.hpp"
#include "robodiff/server/dds_server.hpp"
#include "robodiff/server/http_server.hpp"
#include "robodiff/server/probes.hpp"
#include "robodiff/server/service.hpp"
#include "robodiff/server/service_metrics_text.hpp"
#include "robodiff/server/shm_server.hpp"
#include "dds_exposure.hpp"
#include "dds_socket_binding.hpp"
#include "fleet_setup.hpp"
#include "pause_monitor.hpp"
#include "roudi_watch.hpp"
#include "server_config.hpp"

namespace {

using namespace robodiff::server;

// Signals are taken by sigwait in main, never by a handler: every thread started below
// inherits the blocked mask.
sigset_t blockStopSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGHUP);
  // An ignored signal is dropped even while blocked, so sigwait would never see it: a
  // parent that ignores SIGTERM (nohup, some supervisors) must not make robodiffd unstoppable.
  for (const int sig : {SIGTERM, SIGINT, SIGHUP}) signal(sig, SIG_DFL);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

struct Flags {
  std::string config_file;
  std::vector<std::string> sets;
  std::string cache_dir, instance_id, log_level, log_format, roudi, http;
  int workers = -1, dds_domain = -2;
  bool no_dds = false, no_iceoryx = false, no_http = false, interpreter_only = false, print_config = false;
  double drain_timeout_s = 30;
};

void addFlags(CLI::App& app, Flags& f) {
  app.add_option("--config", f.config_file,
                 "Configuration file (deploy/robodiffd.conf documents every key); default: built-in defaults, "
                 "or $ROBODIFFD_CONFIG");
  app.add_option("--set", f.sets, "Override one setting: section.key=value (repeatable)");
  app.add_option("--cache", f.cache_dir, "Cache directory (cache.dir)");
  app.add_option("--workers", f.workers, "Build worker processes (build.workers)");
  app.add_option("--instance-id", f.instance_id, "This server's id (service.instance_id)");
  app.add_option("--dds-domain", f.dds_domain, "DDS domain id (dds.domain)");
  app.add_flag("--no-dds", f.no_dds, "Do not serve over DDS (dds.enabled = false)");
  app.add_flag("--no-iceoryx", f.no_iceoryx, "Do not serve over iceoryx (iceoryx.enabled = false)");
  app.add_option("--http", f.http, "Serve the dashboard, /metrics, /healthz, /readyz on this IPv4 host:port (http.listen)");
  app.add_flag("--no-http", f.no_http, "No HTTP listener (http.enabled = false)");
  app.add_option("--roudi", f.roudi, "auto | external | embedded | detached (iceoryx.roudi)");
  app.add_flag("--interpreter-only", f.interpreter_only, "Never compile (build.compile = false)");
  app.add_option("--log-level", f.log_level, "debug | info | warn | error (log.level)");
  app.add_option("--log-format", f.log_format, "json | text (log.format)");
  app.add_option("--drain-timeout", f.drain_timeout_s, "Seconds to answer in-flight requests after SIGTERM (30)");
  app.add_flag("--print-config", f.print_config, "Print the effective configuration and exit");
}

ServerConfig configure(const Flags& f) {
  ServerConfig config;
  std::string file = f.config_file;
  if (file.empty())
    if (const char* env = std::getenv("ROBODIFFD_CONFIG"); env != nullptr && *env != '\0') file = env;
  if (!file.empty()) applyConfigFile(config, file);
  for (const std::string& set : f.sets) {
    const auto eq = set.find('=');
    if (eq == std::string::npos) throw ConfigError("--set '" + set + "': expected section.key=value");
    applySetting(config, set.substr(0, eq), set.substr(eq + 1), "--set");
  }
  if (!f.cache_dir.empty()) applySetting(config, "cache.dir", f.cache_dir, "--cache");
  if (f.workers >= 0) applySetting(config, "build.workers", std::to_string(f.workers), "--workers");
  if (!f.instance_id.empty()) applySetting(config, "service.instance_id", f.instance_id, "--instance-id");
  if (f.dds_domain != -2) applySetting(config, "dds.domain", std::to_string(f.dds_domain), "--dds-domain");
  if (f.no_dds) config.dds.enabled = false;
  if (f.no_iceoryx) config.shm.enabled = false;
  if (!f.roudi.empty()) applySetting(config, "iceoryx.roudi", f.roudi, "--roudi");
  if (!f.http.empty()) {
    applySetting(config, "http.listen", f.http, "--http");
    config.http.enabled = true;
  }
  if (f.no_http) config.http.enabled = false;
  if (f.interpreter_only) config.service.compile = false;
  if (!f.log_level.empty()) applySetting(config, "log.level", f.log_level, "--log-level");
  if (!f.log_format.empty()) applySetting(config, "log.format", f.log_format, "--log-format");
  return config;
}

const char* signalName(int sig) {
  switch (sig) {
    case SIGTERM: return "SIGTERM";
    case SIGINT: return "SIGINT";
    case SIGHUP: return "SIGHUP";
  }
  return "signal";
}

// A pause longer than this means RouDi (keep-alive timeout ~1.5 s) has probably dropped us.
constexpr std::chrono::milliseconds kRoudiDropPause{1200};
// How long stopping may outlast the drain timeout before the watchdog ends the process.
constexpr std::chrono::seconds kShutdownGrace{3};

// Keep the cache usable: below this much free space the server is not ready.
constexpr std::uint64_t kCacheMinFreeBytes = std::uint64_t{64} << 20;

// The DDS Security identity of dds.security, or none (open DDS) when the exposure policy
// allows it (dds_exposure.hpp); throws ConfigError when it does not.
robodiff::dds_codec::DdsSecurity ddsSecurity(const robodiff::server::DdsSettings& dds, Logger& log) {
  const char* uri = std::getenv("CYCLONEDDS_URI");
  robodiff::server::DdsExposure exposure;
  exposure.secure = !dds.security.empty();
  exposure.loopback_only = robodiff::server::cycloneLoopbackOnly(uri);
  exposure.allow_unauthenticated = dds.allow_unauthenticated;
  if (auto refusal = robodiff::server::ddsExposureRefusal(exposure)) throw ConfigError(*refusal);
  if (exposure.secure) {
    try {
      return robodiff::dds_codec::keystoreIdentity(dds.security, dds.security_identity);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(std::string("dds.security: ") + e.what());
    }
  }
  log.warn("dds_open", {{"loopback_only", exposure.loopback_only},
                        {"message", exposure.loopback_only
                                        ? "DDS is open (no DDS Security): any process on this host can call "
                                          "robodiffd over DDS; set dds.security (deploy/security.md) to require "
                                          "certificates"
                                        : "DDS is open (no DDS Security) and reachable from other hosts "
                                          "(dds.allow_unauthenticated = true): anyone on those networks can call "
                                          "robodiffd"}});
  return {};
}

// Binds the DDS participant's UDP sockets to the one device its configuration names
// (dds_socket_binding.hpp), and logs what was done or why not.
void confineDdsSockets(Logger& log) {
  const auto device = robodiff::server::cycloneSingleDevice(std::getenv("CYCLONEDDS_URI"));
  if (!device) {
    log.info("dds_sockets_unconfined",
             {{"message", "the Cyclone configuration names several interfaces or lets Cyclone choose: its sockets "
                          "accept packets from every interface; confine the unit with RestrictNetworkInterfaces= "
                          "(deploy/security.md)"}});
    return;
  }
  const auto bound = robodiff::server::bindUdpSocketsToDevice(*device);
  std::string sockets;
  for (const std::string& s : bound.sockets) sockets += (sockets.empty() ? "" : ", ") + s;
  if (!bound.error.empty())
    log.warn("dds_sockets_not_confined", {{"device", *device}, {"bound", sockets}, {"error", bound.error}});
  else
    log.info("dds_sockets_confined", {{"device", *device}, {"sockets", sockets}});
}

// The readiness checks: RouDi (iceoryx on), the DDS participant (DDS on), the cache
// directory, and the service itself serving (not starting, not draining).
void addReadinessChecks(Probes& probes, const ServerConfig& config, const Service& service, const DdsServer* dds,
                        const std::filesystem::path& cache_dir, const std::atomic<bool>& iceoryx_lost) {
  probes.addReadinessCheck("service", [&service]() -> ProbeResult {
    const auto state = service.state();
    if (state == robodiff::rpc::ServingState::Serving) return {true, ""};
    return {false, std::string("state ") + robodiff::rpc::toString(state)};
  });
  if (config.shm.enabled)
    probes.addReadinessCheck("roudi", [&iceoryx_lost]() -> ProbeResult {
      if (iceoryx_lost) return {false, "RouDi no longer knows robodiffd (a pause or a RouDi restart); it is stopping to be restarted"};
      if (robodiff::shm::roudiRunning()) return {true, ""};
      return {false, "RouDi does not answer on " + robodiff::shm::roudiSocketPath() +
                         "; iceoryx clients cannot connect"};
    });
  if (dds != nullptr)
    probes.addReadinessCheck("dds", [dds]() -> ProbeResult {
      const robodiff::Status ready = dds->ready();
      return {ready.ok(), ready.message};
    });
  probes.addReadinessCheck("cache", [cache_dir] { return checkDirectoryWritable(cache_dir, kCacheMinFreeBytes); });
}

// A submitted job's kind and parameters are checked before it is queued.
robodiff::Status validateJob(const std::string& kind, const std::string& params_json,
                             const std::vector<std::filesystem::path>& readable_dirs) {
  try {
    robodiff::batch::validateBatchJob(kind, nlohmann::json::parse(params_json),
                                      robodiff::batch::FileAccess::under(readable_dirs));
    return {};
  } catch (const std::exception& e) {
    return {robodiff::StatusCode::InvalidArgument, "SubmitJob " + kind + ": " + robodiff::language::jsonProblem(e.what())};
  }
}

// The running daemon: the service, its transports and the operators' HTTP endpoints,
// started in that order and stopped in the reverse one.
class Daemon {
 public:
  Daemon(ServerConfig& config, Logger& log, robodiff::dds_codec::DdsSecurity dds_security)
      : config_(config), log_(log), dds_security_(std::move(dds_security)), service_(serviceOptions(config, log), log) {}

  void start() {
    if (config_.shm.enabled) startShm();
    if (config_.dds.enabled) startDds();
    if (config_.http.enabled) startHttp();
    service_.markServing();
  }

  const Service& service() const { return service_; }
  bool iceoryxLost() const { return iceoryx_lost_; }

  // Drains after `sig` (new requests get UNAVAILABLE, those in flight are answered) and
  // stops; returns the exit code. Exits 4 at once when RouDi no longer knows this process.
  int drainAndStop(int sig, double drain_timeout_s) {
    log_.info("draining", {{"signal", signalName(sig)}, {"iceoryx_lost", iceoryx_lost_.load()}});
    service_.beginDrain();
    if (shm_) shm_->stopAccepting();
    if (dds_) dds_->stopAccepting();
    const auto drain_timeout = std::chrono::milliseconds(static_cast<long long>(drain_timeout_s * 1000));
    armShutdownWatchdog(drain_timeout + kShutdownGrace, 3);
    const bool idle = waitIdle(std::chrono::steady_clock::now() + drain_timeout);
    if (!idle) log_.warn("drain_timeout", {{"seconds", drain_timeout_s}});
    if (http_) http_->stop();  // its checks read the transports and the service
    if (dds_) dds_->stop();
    if (iceoryx_lost_) {  // its ports' memory is RouDi's again: touching them would abort
      shm_.release();
      log_.info("stopped", {{"clean", idle}, {"exit_code", 4}});
      std::fflush(nullptr);
      std::_Exit(4);  // no static destructors: the iceoryx runtime's would touch them too
    }
    if (shm_) shm_->stop();
    dds_.reset();
    shm_.reset();
    log_.info("stopped", {{"clean", idle}});
    return idle ? 0 : 3;
  }

 private:
  static ServiceOptions serviceOptions(const ServerConfig& config, Logger& log) {
    ServiceOptions options = config.service;
    options.validate_job = validateJob;
    applyFleetSettings(config, options, log);
    return options;
  }

  void startShm() {
    // A RouDi started here must outlive this process's iceoryx runtime, which unregisters
    // from it at exit (a static destroyed then): a static made before the runtime is
    // destroyed after it.
    static std::unique_ptr<RoudiHandle> roudi;
    roudi = ensureRoudi(parseRoudiMode(config_.shm.roudi), log_);
    ShmServerOptions options;
    options.service = config_.shm.service;
    options.fair = {config_.limits.max_queued_requests_per_client, config_.limits.max_running_requests_per_client};
    options.error_replies_per_second = config_.limits.error_replies_per_second;
    options.sessions.max_sessions = config_.limits.max_shm_sessions;
    shm_ = std::make_unique<ShmServer>(service_, options, log_);
    if (const robodiff::Status started = shm_->start(); !started.ok())
      throw std::runtime_error("iceoryx: " + started.message);
    // Paused past RouDi's keep-alive timeout, or RouDi replaced: the iceoryx runtime is lost
    // either way; the usual drain follows (the main thread's sigwait takes SIGTERM).
    auto lose_iceoryx = [this](const std::string& reason) {
      if (iceoryx_lost_.exchange(true)) return;
      log_.error("iceoryx_lost", {{"reason", reason},
                                  {"message", "RouDi no longer knows robodiffd; draining the other transports and "
                                              "exiting with 4 for the supervisor to restart it"}});
      ::kill(::getpid(), SIGTERM);
    };
    pause_monitor_ = std::make_unique<PauseMonitor>(kRoudiDropPause, [lose_iceoryx](double seconds) {
      lose_iceoryx("paused for " + std::to_string(seconds) + " s, past RouDi's keep-alive timeout");
    });
    roudi_watch_ = std::make_unique<RoudiWatch>(lose_iceoryx);
  }

  void startDds() {
    DdsServerOptions options;
    if (config_.dds.domain >= 0) options.domain_id = static_cast<std::uint32_t>(config_.dds.domain);
    options.service_name = config_.dds.service;
    options.max_sample_bytes = config_.dds.max_sample_bytes;
    options.security = dds_security_;
    options.fair = {config_.limits.max_queued_requests_per_client, config_.limits.max_running_requests_per_client};
    options.error_replies_per_second = config_.limits.error_replies_per_second;
    dds_ = std::make_unique<DdsServer>(service_, options, log_);
    dds_->start();
    confineDdsSockets(log_);
  }

  // Operators' HTTP endpoints; not fatal when they cannot listen (the transports are the
  // service; a probe that cannot connect shows the problem).
  void startHttp() {
    probes_.setLivenessNote([this] {
      return service_.state() == robodiff::rpc::ServingState::Draining ? std::string("draining") : std::string();
    });
    const std::filesystem::path cache_dir =
        config_.service.cache_dir.empty() ? robodiff::cache::defaultCacheDir() : config_.service.cache_dir;
    addReadinessChecks(probes_, config_, service_, dds_.get(), cache_dir, iceoryx_lost_);
    HttpServerOptions options;
    options.host = config_.http.host;
    options.port = config_.http.port;
    options.allowed_hosts = config_.http.allowed_hosts;
    http_ = std::make_unique<HttpServer>(options);
    http_->route("/metrics", [this](const HttpRequest&) {
      HttpResponse r;
      r.content_type = kPrometheusContentType;
      r.body = serviceMetricsText(service_.metrics());
      return r;
    });
    probes_.routeOn(*http_);
    routeDashboard(*http_, service_);
    try {
      http_->start();
      log_.info("http_listening", {{"address", http_->address()},
                                   {"port", static_cast<long long>(http_->port())},
                                   {"dashboard", "http://" + http_->address() + "/"},
                                   {"paths", "/ /api/overview /api/history /metrics /healthz /readyz"}});
    } catch (const std::exception& e) {
      log_.error("http_failed", {{"message", e.what()}});
      http_.reset();
    }
  }

  // Waits for the service and each transport to have nothing in flight, until `deadline`.
  bool waitIdle(std::chrono::steady_clock::time_point deadline) {
    auto left = [&] {
      return std::chrono::duration_cast<std::chrono::milliseconds>(
          std::max(deadline - std::chrono::steady_clock::now(), std::chrono::steady_clock::duration::zero()));
    };
    bool idle = service_.waitIdle(left());
    if (shm_ && !iceoryx_lost_) idle = shm_->waitIdle(left()) && idle;
    if (dds_) idle = dds_->waitIdle(left()) && idle;
    return idle;
  }

  ServerConfig& config_;
  Logger& log_;
  const robodiff::dds_codec::DdsSecurity dds_security_;
  Service service_;
  std::atomic<bool> iceoryx_lost_{false};
  std::unique_ptr<ShmServer> shm_;
  std::unique_ptr<PauseMonitor> pause_monitor_;
  std::unique_ptr<RoudiWatch> roudi_watch_;
  std::unique_ptr<DdsServer> dds_;
  Probes probes_;
  std::unique_ptr<HttpServer> http_;
};

// The configuration from the flags (embedded defaults, a file, --set and the shortcut
// flags); an exit code when there is nothing to serve (help, --print-config, an error).
std::optional<int> configureFromFlags(int argc, char** argv, Flags& flags, ServerConfig& config) {
  CLI::App app{"robodiffd: the robodiff service (derivatives of robot dynamics over iceoryx and DDS)"};
  addFlags(app, flags);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    config = configure(flags);
  } catch (const std::exception& e) {
    std::cerr << "robodiffd: " << e.what() << "\n";
    return 2;
  }
  if (flags.print_config) {
    std::cout << formatConfig(config);
    return 0;
  }
  if (!config.shm.enabled && !config.dds.enabled) {
    std::cerr << "robodiffd: both transports are disabled (iceoryx.enabled and dds.enabled are false); "
                 "nothing would reach the service\n";
    return 2;
  }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  const sigset_t stop_signals = blockStopSignals();
  Flags flags;
  ServerConfig config;
  if (const std::optional<int> exit_code = configureFromFlags(argc, argv, flags, config)) return *exit_code;
  Logger log(stderr, config.log_level, config.log_format);
  robodiff::dds_codec::DdsSecurity dds_security;
  try {
    if (config.dds.enabled) dds_security = ddsSecurity(config.dds, log);
  } catch (const std::exception& e) {
    log.error("startup_refused", {{"message", e.what()}});
    return 2;
  }
  const auto started = std::chrono::steady_clock::now();
  try {
    Daemon daemon(config, log, dds_security);
    daemon.start();
    log.info("serving", {{"instance_id", daemon.service().instanceId()},
                         {"iceoryx", config.shm.enabled},
                         {"dds", config.dds.enabled},
                         {"dds_domain", static_cast<long long>(config.dds.domain)},
                         {"startup_seconds",
                          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()}});
    int sig = 0;
    sigwait(&stop_signals, &sig);
    return daemon.drainAndStop(sig, flags.drain_timeout_s);
  } catch (const ConfigError& e) {  // the settings do not fit together (e.g. [fleet]'s role)
    log.error("startup_refused", {{"message", e.what()}});
    return 2;
  } catch (const std::exception& e) {
    log.error("startup_failed", {{"message", e.what()}});
    return 1;
  }
}
