#pragma once
// robodiffd's configuration: every setting with its default, read from a file
// (deploy/robodiffd.conf documents each one), then overridden by flags. The defaults are
// good for one host; with no file at all robodiffd runs on them.
//
// The file is TOML (read with toml++, config_file.cpp): "[section]" tables of
// "key = value" pairs. Counts are integers, flags booleans, names strings. Sizes and
// durations are strings with a unit ("512KiB", "4GiB"; "500ms", "30s", "15min") or plain
// integers: bytes, seconds. An unknown section or key, a value of the wrong TOML type or
// one that does not parse, and a TOML syntax error are errors naming the file, the line
// and column, the key and the value.

#include <chrono>
#include <cstdint>
#include <filesystem>
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

// A fleet (docs/fleet.md): build hosts compile and sign, robot hosts fetch over DDS.
struct FleetSettings {
  std::string role = "standalone";  // standalone | build | robot
  // role = build
  std::string signing_key;          // Ed25519 private key file (robodiff keygen)
  bool build_for_robots = true;     // build what a robot asks for and this host lacks
  std::uint32_t max_builds_per_robot = 4;
  std::uint64_t chunk_size = 256 * 1024;
  std::chrono::milliseconds chunk_delay{0};  // failover drills and tests only
  // role = robot
  std::vector<std::string> build_hosts;  // the build hosts' dds.service names, preferred first
  std::vector<std::filesystem::path> trusted_keys;  // public key files or directories of *.pub
  std::string target = "auto";           // auto | x86-64-v2 | x86-64-v3 | x86-64-v4
  std::string security_identity;         // with dds.security: this robot's client identity
  bool fetch_sources = false;
  std::chrono::milliseconds call_timeout = std::chrono::seconds(5);
  std::chrono::milliseconds build_wait = std::chrono::minutes(20);
  std::uint64_t max_artifact = std::uint64_t{256} << 20;
};

struct ServerConfig {
  ServiceOptions service;
  ClientLimits limits;
  ShmSettings shm;
  DdsSettings dds;
  HttpSettings http;
  FleetSettings fleet;
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

// Applies one setting given as text ("service.request_threads", "8"; quotes around the
// value are dropped), as --set does; `where` names its origin in errors ("--set").
// Throws ConfigError.
void applySetting(ServerConfig& config, const std::string& key, const std::string& value, const std::string& where);

// Applies every setting of a TOML text; `source` names it in errors. Throws ConfigError
// (toml++'s syntax errors included).
void applyConfigText(ServerConfig& config, const std::string& text, const std::string& source);
void applyConfigFile(ServerConfig& config, const std::string& path);

// The effective configuration as a TOML file (every key, with its value), which
// applyConfigText reads back to the same configuration.
std::string formatConfig(const ServerConfig& config);

// Every key, "section.key", in file order.
std::vector<std::string> configKeys();

}  // namespace robodiff::server
