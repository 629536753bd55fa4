// The settings table: one entry per key, which parses its value's text into ServerConfig
// and prints it back (config_settings.hpp); --set and --print-config on top of it. The
// file reader is config_file.cpp.
#include "server_config.hpp"

#include <arpa/inet.h>

#include <type_traits>

#include "config_settings.hpp"
#include "config_values.hpp"

namespace robodiff::server {
namespace {

using namespace config_values;

// Each helper takes `field`, a generic lambda naming the member ([](auto& c) -> auto& {...}),
// so that one accessor serves both parsing (ServerConfig&) and printing (const ServerConfig&).
template <class Field>
Setting textSetting(const char* key, Field field) {
  return {key, ValueKind::Text, [field](ServerConfig& c, const std::string& v) { field(c) = v; },
          [field](const ServerConfig& c) { return std::string(field(c)); }};
}

template <class Field>
Setting flagSetting(const char* key, Field field) {
  return {key, ValueKind::Flag, [field](ServerConfig& c, const std::string& v) { field(c) = parseBool(v); },
          [field](const ServerConfig& c) { return std::string(field(c) ? "true" : "false"); }};
}

template <class Field>
Setting countSetting(const char* key, Field field, std::uint64_t min, std::uint64_t max) {
  return {key, ValueKind::Count,
          [field, min, max](ServerConfig& c, const std::string& v) {
            const std::uint64_t n = parseUnsigned(v, max);
            if (n < min) throw std::invalid_argument("must be at least " + std::to_string(min));
            auto& target = field(c);
            target = static_cast<std::remove_reference_t<decltype(target)>>(n);
          },
          [field](const ServerConfig& c) { return std::to_string(field(c)); }};
}

template <class Field>
Setting sizeSetting(const char* key, Field field) {
  return {key, ValueKind::Size,
          [field](ServerConfig& c, const std::string& v) {
            auto& target = field(c);
            target = static_cast<std::remove_reference_t<decltype(target)>>(parseBytes(v));
          },
          [field](const ServerConfig& c) { return formatBytes(field(c)); }};
}

template <class Field>
Setting durationSetting(const char* key, Field field) {
  return {key, ValueKind::Duration, [field](ServerConfig& c, const std::string& v) { field(c) = parseDuration(v); },
          [field](const ServerConfig& c) { return formatDuration(field(c)); }};
}

// Counts bounded by what the service can hold; per-client limits start at 1.
constexpr std::uint64_t kMillion = 1u << 20;

std::vector<Setting> serviceSettings() {
  return {
      textSetting("service.instance_id", [](auto& c) -> auto& { return c.service.instance_id; }),
      countSetting("service.request_threads", [](auto& c) -> auto& { return c.service.request_threads; }, 0, 256),
      countSetting("service.request_queue", [](auto& c) -> auto& { return c.service.request_queue_capacity; }, 0, kMillion),
      countSetting("service.batch_threads", [](auto& c) -> auto& { return c.service.batch_threads; }, 0, 256),
      countSetting("service.background_nice", [](auto& c) -> auto& { return c.service.background_nice; }, 0, 19),
      countSetting("service.max_batch_knots", [](auto& c) -> auto& { return c.service.max_batch_knots; }, 0, 100'000'000),
      countSetting("service.max_models", [](auto& c) -> auto& { return c.service.max_models; }, 0, kMillion),
      countSetting("service.max_functions", [](auto& c) -> auto& { return c.service.max_functions; }, 0, kMillion),
      sizeSetting("service.max_urdf", [](auto& c) -> auto& { return c.service.max_urdf_bytes; }),
      // Limits of the URDFs LoadModel accepts (ServiceOptions::urdf_limits).
      countSetting("service.max_urdf_depth", [](auto& c) -> auto& { return c.service.urdf_limits.max_depth; }, 0, 1u << 30),
      countSetting("service.max_urdf_elements", [](auto& c) -> auto& { return c.service.urdf_limits.max_elements; }, 0, 1u << 30),
      countSetting("service.max_urdf_links", [](auto& c) -> auto& { return c.service.urdf_limits.max_links; }, 0, 1u << 30),
      countSetting("service.max_urdf_joints", [](auto& c) -> auto& { return c.service.urdf_limits.max_joints; }, 0, 1u << 30),
      countSetting("service.max_urdf_name_length",
                   [](auto& c) -> auto& { return c.service.urdf_limits.max_name_length; }, 0, 1u << 30),
      countSetting("service.max_urdf_attribute_length",
                   [](auto& c) -> auto& { return c.service.urdf_limits.max_attribute_length; }, 0, 1u << 30),
      sizeSetting("service.max_spec", [](auto& c) -> auto& { return c.service.max_spec_bytes; }),
  };
}

std::vector<Setting> limitSettings() {
  return {
      // The transports' fair sharing (ServerConfig::limits).
      countSetting("limits.max_queued_requests_per_client",
                   [](auto& c) -> auto& { return c.limits.max_queued_requests_per_client; }, 1, kMillion),
      countSetting("limits.max_running_requests_per_client",
                   [](auto& c) -> auto& { return c.limits.max_running_requests_per_client; }, 1, kMillion),
      countSetting("limits.error_replies_per_second", [](auto& c) -> auto& { return c.limits.error_replies_per_second; },
                   1, kMillion),
      // Each session is an iceoryx server port and a WaitSet attachment (256 per WaitSet).
      countSetting("limits.max_shm_sessions", [](auto& c) -> auto& { return c.limits.max_shm_sessions; }, 1, 250),
      countSetting("limits.max_models_per_client", [](auto& c) -> auto& { return c.service.max_models_per_client; }, 0,
                   kMillion),
      countSetting("limits.max_functions_per_client",
                   [](auto& c) -> auto& { return c.service.max_functions_per_client; }, 0, kMillion),
  };
}

std::vector<Setting> buildAndJobSettings() {
  return {
      countSetting("build.workers", [](auto& c) -> auto& { return c.service.build_workers; }, 0, 256),
      flagSetting("build.compile", [](auto& c) -> auto& { return c.service.compile; }),
      textSetting("build.compiler", [](auto& c) -> auto& { return c.service.compiler; }),
      textSetting("build.worker_executable", [](auto& c) -> auto& { return c.service.worker_executable; }),
      durationSetting("build.timeout", [](auto& c) -> auto& { return c.service.build_timeout; }),
      sizeSetting("build.memory_limit", [](auto& c) -> auto& { return c.service.compiler_memory_limit_bytes; }),
      countSetting("jobs.workers", [](auto& c) -> auto& { return c.service.job_workers; }, 0, 256),
      durationSetting("jobs.timeout", [](auto& c) -> auto& { return c.service.job_timeout; }),
      sizeSetting("jobs.memory_limit", [](auto& c) -> auto& { return c.service.job_memory_limit_bytes; }),
      {"jobs.data_dirs", ValueKind::Text,
       [](ServerConfig& c, const std::string& v) { c.service.job_data_dirs = parseDirectoryList(v); },
       [](const ServerConfig& c) { return formatDirectoryList(c.service.job_data_dirs); }},
      textSetting("cache.dir", [](auto& c) -> auto& { return c.service.cache_dir; }),
      sizeSetting("cache.budget", [](auto& c) -> auto& { return c.service.cache_budget_bytes; }),
  };
}

std::vector<Setting> transportSettings() {
  return {
      flagSetting("iceoryx.enabled", [](auto& c) -> auto& { return c.shm.enabled; }),
      textSetting("iceoryx.service", [](auto& c) -> auto& { return c.shm.service; }),
      {"iceoryx.roudi", ValueKind::Text,
       [](ServerConfig& c, const std::string& v) {
         if (v != "auto" && v != "external" && v != "embedded" && v != "detached")
           throw std::invalid_argument("is not one of auto, external, embedded, detached");
         c.shm.roudi = v;
       },
       [](const ServerConfig& c) { return c.shm.roudi; }},
      flagSetting("dds.enabled", [](auto& c) -> auto& { return c.dds.enabled; }),
      {"dds.domain", ValueKind::DomainId,
       [](ServerConfig& c, const std::string& v) {
         c.dds.domain = v == "default" ? -1 : static_cast<std::int32_t>(parseUnsigned(v, 232));
       },
       [](const ServerConfig& c) { return c.dds.domain < 0 ? std::string("default") : std::to_string(c.dds.domain); }},
      textSetting("dds.service", [](auto& c) -> auto& { return c.dds.service; }),
      sizeSetting("dds.max_sample", [](auto& c) -> auto& { return c.dds.max_sample_bytes; }),
      textSetting("dds.security", [](auto& c) -> auto& { return c.dds.security; }),
      textSetting("dds.security_identity", [](auto& c) -> auto& { return c.dds.security_identity; }),
      flagSetting("dds.allow_unauthenticated", [](auto& c) -> auto& { return c.dds.allow_unauthenticated; }),
  };
}

std::vector<Setting> httpAndLogSettings() {
  return {
      flagSetting("http.enabled", [](auto& c) -> auto& { return c.http.enabled; }),
      {"http.listen", ValueKind::Text, [](ServerConfig& c, const std::string& v) { parseListenAddress(v, c.http); },
       [](const ServerConfig& c) { return c.http.host + ":" + std::to_string(c.http.port); }},
      {"http.allowed_hosts", ValueKind::Text,
       [](ServerConfig& c, const std::string& v) { c.http.allowed_hosts = parseNameList(v); },
       [](const ServerConfig& c) { return formatNameList(c.http.allowed_hosts); }},
      {"log.level", ValueKind::Text, [](ServerConfig& c, const std::string& v) { c.log_level = parseLogLevel(v); },
       [](const ServerConfig& c) { return std::string(toString(c.log_level)); }},
      {"log.format", ValueKind::Text, [](ServerConfig& c, const std::string& v) { c.log_format = parseLogFormat(v); },
       [](const ServerConfig& c) { return std::string(c.log_format == LogFormat::Json ? "json" : "text"); }},
  };
}

std::vector<Setting> fleetSettings() {
  return {
      {"fleet.role", ValueKind::Text,
       [](ServerConfig& c, const std::string& v) {
         if (v != "standalone" && v != "build" && v != "robot")
           throw std::invalid_argument("is not one of standalone, build, robot");
         c.fleet.role = v;
       },
       [](const ServerConfig& c) { return c.fleet.role; }},
      textSetting("fleet.signing_key", [](auto& c) -> auto& { return c.fleet.signing_key; }),
      flagSetting("fleet.build_for_robots", [](auto& c) -> auto& { return c.fleet.build_for_robots; }),
      countSetting("fleet.max_builds_per_robot", [](auto& c) -> auto& { return c.fleet.max_builds_per_robot; }, 1, 1024),
      sizeSetting("fleet.chunk_size", [](auto& c) -> auto& { return c.fleet.chunk_size; }),
      durationSetting("fleet.chunk_delay", [](auto& c) -> auto& { return c.fleet.chunk_delay; }),
      {"fleet.build_hosts", ValueKind::Text,
       [](ServerConfig& c, const std::string& v) { c.fleet.build_hosts = parseServiceNames(v); },
       [](const ServerConfig& c) { return formatNameList(c.fleet.build_hosts); }},
      {"fleet.trusted_keys", ValueKind::Text,
       [](ServerConfig& c, const std::string& v) { c.fleet.trusted_keys = parseDirectoryList(v); },
       [](const ServerConfig& c) { return formatDirectoryList(c.fleet.trusted_keys); }},
      textSetting("fleet.target", [](auto& c) -> auto& { return c.fleet.target; }),
      textSetting("fleet.security_identity", [](auto& c) -> auto& { return c.fleet.security_identity; }),
      flagSetting("fleet.fetch_sources", [](auto& c) -> auto& { return c.fleet.fetch_sources; }),
      durationSetting("fleet.call_timeout", [](auto& c) -> auto& { return c.fleet.call_timeout; }),
      durationSetting("fleet.build_wait", [](auto& c) -> auto& { return c.fleet.build_wait; }),
      sizeSetting("fleet.max_artifact", [](auto& c) -> auto& { return c.fleet.max_artifact; }),
  };
}

// How --print-config writes a value: counts, flags and domain numbers bare, the rest as
// TOML strings.
std::string tomlValue(const Setting& setting, const std::string& text) {
  const bool bare = setting.kind == ValueKind::Count || setting.kind == ValueKind::Flag ||
                    (setting.kind == ValueKind::DomainId && text != "default");
  return bare ? text : tomlString(text);
}

}  // namespace

const std::vector<Setting>& settings() {
  static const std::vector<Setting> table = [] {
    std::vector<Setting> all;
    for (auto part : {serviceSettings(), limitSettings(), buildAndJobSettings(), transportSettings(),
                      httpAndLogSettings(), fleetSettings()})
      all.insert(all.end(), part.begin(), part.end());
    return all;
  }();
  return table;
}

const Setting* findSetting(const std::string& key) {
  for (const Setting& s : settings())
    if (key == s.key) return &s;
  return nullptr;
}

std::string sectionOf(const std::string& key) { return key.substr(0, key.find('.')); }

std::vector<std::string> sectionNames() {
  std::vector<std::string> sections;
  for (const Setting& s : settings())
    if (sections.empty() || sections.back() != sectionOf(s.key)) sections.push_back(sectionOf(s.key));
  return sections;
}

std::vector<std::string> keysOf(const std::string& section) {
  std::vector<std::string> keys;
  for (const Setting& s : settings())
    if (sectionOf(s.key) == section) keys.push_back(std::string(s.key).substr(section.size() + 1));
  return keys;
}

std::string expectedValue(const Setting& setting) {
  const std::string key = std::string(setting.key).substr(sectionOf(setting.key).size() + 1);
  switch (setting.kind) {
    case ValueKind::Text: return "a string in double quotes";
    case ValueKind::Flag: return "true or false, unquoted (e.g. " + key + " = true)";
    case ValueKind::Count: return "a whole number, unquoted (e.g. " + key + " = 2)";
    case ValueKind::Size: return "a size: a string with a unit (e.g. " + key + " = \"512KiB\") or a whole number of bytes";
    case ValueKind::Duration:
      return "a duration: a string with a unit (e.g. " + key + " = \"30s\") or a whole number of seconds";
    case ValueKind::DomainId: return "a domain id 0..232 or the string \"default\"";
  }
  return "";
}

void parseSettingValue(const Setting& setting, ServerConfig& config, const std::string& value,
                       const std::string& where) {
  try {
    setting.parse(config, value);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(where + ": " + setting.key + " = '" + value + "' " + e.what());
  }
}

void parseListenAddress(const std::string& value, HttpSettings& http) {
  const auto colon = value.rfind(':');
  if (colon == std::string::npos) throw std::invalid_argument("is not host:port (e.g. 127.0.0.1:9464)");
  const std::string host = value.substr(0, colon), port = value.substr(colon + 1);
  in_addr address{};
  if (::inet_pton(AF_INET, host.c_str(), &address) != 1)
    throw std::invalid_argument("has host '" + host + "', not an IPv4 address (e.g. 127.0.0.1, 0.0.0.0)");
  std::uint64_t number = 0;
  try {
    number = parseUnsigned(port, 65535);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("has port '" + port + "' that " + e.what() + " (0..65535; 0: any free port)");
  }
  http.host = host;
  http.port = static_cast<std::uint16_t>(number);
}

std::vector<std::string> configKeys() {
  std::vector<std::string> keys;
  for (const Setting& s : settings()) keys.push_back(s.key);
  return keys;
}

void applySetting(ServerConfig& config, const std::string& key, const std::string& raw_value,
                  const std::string& where) {
  const Setting* setting = findSetting(key);
  if (setting == nullptr) {
    const std::string closest = closestName(key, configKeys());
    throw ConfigError(where + ": unknown setting '" + key + "'" +
                      (closest.empty() ? "" : " (did you mean '" + closest + "'?)") + "; known: " + joined(configKeys()));
  }
  std::string value = trim(raw_value);
  if (value.size() >= 2 && value.front() == '"' && value.back() == '"') value = value.substr(1, value.size() - 2);
  parseSettingValue(*setting, config, value, where);
}

std::string formatConfig(const ServerConfig& config) {
  std::string out, section;
  for (const Setting& s : settings()) {
    const std::string key = s.key;
    const std::string sec = sectionOf(key);
    if (sec != section) {
      out += (section.empty() ? "" : "\n") + std::string("[") + sec + "]\n";
      section = sec;
    }
    out += key.substr(sec.size() + 1) + " = " + tomlValue(s, s.format(config)) + "\n";
  }
  return out;
}

}  // namespace robodiff::server
