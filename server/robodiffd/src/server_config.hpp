#pragma once
// robodiffd's configuration: every setting with its default, read from a file
// (deploy/robodiffd.conf documents each one), then overridden by flags. The defaults are
// good for one host; with no file at all robodiffd runs on them.
//
// File format: "[section]" lines and "key = value" lines; '#' starts a comment; values
// may be quoted ("..."). Sizes take units (512KiB, 4GiB), durations too (500ms, 30s,
// 15min). An unknown section or key, or a value that does not parse, is an error naming
// the file, the line, the key and the value.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "robodiff/server/log.hpp"
#include "robodiff/server/service.hpp"

namespace robodiff::server {

struct ShmSettings {
  bool enabled = true;
  std::string service = "robodiff";  // the iceoryx service name
  std::string roudi = "auto";        // auto | external | embedded
};

struct DdsSettings {
  bool enabled = true;
  std::int32_t domain = -1;          // -1: Cyclone's default (CYCLONEDDS_URI may set it)
  std::string service = "robodiff";  // topic prefix
  std::uint64_t max_sample_bytes = 512 * 1024;  // EvaluateBatch replies beyond are split
  std::string security;                     // DDS Security keystore directory; "": open DDS
  std::string security_identity = "robodiffd";  // the server's identity in that keystore
  bool allow_unauthenticated = false;       // open DDS although it reaches other hosts
};

// The HTTP listener for operators: GET /metrics (Prometheus), /healthz, /readyz.
struct HttpSettings {
  bool enabled = true;
  std::string host = "127.0.0.1";  // IPv4; loopback by default: nothing is exposed off the host
  std::uint16_t port = 9464;       // 0: an ephemeral port (logged as http_listening)
  std::vector<std::string> allowed_hosts;  // Host names accepted besides IPs, localhost, hostname
};

// Fair sharing between clients over both transports (docs/limits.md, "Fair sharing"): a
// client is an iceoryx client port or a DDS writer.
struct ClientLimits {
  std::uint32_t max_queued_requests_per_client = 64;   // pending (queued or running); more: RESOURCE_EXHAUSTED
  std::uint32_t max_running_requests_per_client = 2;   // posted requests on the request threads at once
  std::uint32_t error_replies_per_second = 100;        // per client, to malformed / over-quota requests
  std::uint32_t max_shm_sessions = 64;                 // iceoryx connections (sessions) open at once
};

struct ServerConfig {
  ServiceOptions service;
  ClientLimits limits;
  ShmSettings shm;
  DdsSettings dds;
  HttpSettings http;
  LogLevel log_level = LogLevel::Info;
  LogFormat log_format = LogFormat::Json;
};

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "host:port" (IPv4 dotted quad, port 0..65535) into `http`; std::invalid_argument saying
// what is wrong otherwise.
void parseListenAddress(const std::string& value, HttpSettings& http);

// Applies one setting ("service.request_threads", "8"); `where` names its origin in
// errors ("robodiffd.conf:12", "--set"). Throws ConfigError.
void applySetting(ServerConfig& config, const std::string& key, const std::string& value, const std::string& where);

// Applies every setting of a configuration text; `source` names it in errors.
void applyConfigText(ServerConfig& config, const std::string& text, const std::string& source);
void applyConfigFile(ServerConfig& config, const std::string& path);

// The effective configuration in the file format (every key, with its value).
std::string formatConfig(const ServerConfig& config);

// Every key, "section.key", in file order.
std::vector<std::string> configKeys();

}  // namespace robodiff::server
