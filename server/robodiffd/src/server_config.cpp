// The settings table: one entry per key, which parses its value into ServerConfig and
// prints it back. The file reader, --set and --print-config all go through it.
#include "server_config.hpp"

#include <arpa/inet.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

namespace robodiff::server {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

// A number and a unit suffix: "512KiB" -> (512, "KiB").
bool splitNumber(const std::string& text, double& number, std::string& unit) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  number = std::strtod(begin, &end);
  if (end == begin || errno != 0 || !std::isfinite(number) || number < 0) return false;
  unit = trim(std::string(end));
  return true;
}

std::uint64_t parseUnsigned(const std::string& value, std::uint64_t max) {
  if (value.empty() || value.find_first_not_of("0123456789") != std::string::npos)
    throw std::invalid_argument("is not a whole number");
  errno = 0;
  const unsigned long long n = std::strtoull(value.c_str(), nullptr, 10);
  if (errno != 0 || n > max) throw std::invalid_argument("is beyond " + std::to_string(max));
  return n;
}

std::uint64_t parseBytes(const std::string& value) {
  double n = 0;
  std::string unit;
  if (!splitNumber(value, n, unit)) throw std::invalid_argument("is not a size (e.g. 512KiB, 4GiB)");
  double scale = 0;
  if (unit.empty() || unit == "B") scale = 1;
  else if (unit == "KiB" || unit == "K") scale = 1024.0;
  else if (unit == "MiB" || unit == "M") scale = 1024.0 * 1024;
  else if (unit == "GiB" || unit == "G") scale = 1024.0 * 1024 * 1024;
  else if (unit == "KB") scale = 1e3;
  else if (unit == "MB") scale = 1e6;
  else if (unit == "GB") scale = 1e9;
  else throw std::invalid_argument("has unit '" + unit + "'; use B, KiB, MiB, GiB, KB, MB or GB");
  return static_cast<std::uint64_t>(std::llround(n * scale));
}

std::chrono::milliseconds parseDuration(const std::string& value) {
  double n = 0;
  std::string unit;
  if (!splitNumber(value, n, unit)) throw std::invalid_argument("is not a duration (e.g. 500ms, 30s, 15min)");
  double ms = 0;
  if (unit == "ms") ms = n;
  else if (unit == "s" || unit.empty()) ms = n * 1e3;
  else if (unit == "min") ms = n * 60e3;
  else if (unit == "h") ms = n * 3600e3;
  else throw std::invalid_argument("has unit '" + unit + "'; use ms, s, min or h");
  return std::chrono::milliseconds(static_cast<std::int64_t>(std::llround(ms)));
}

bool parseBool(const std::string& value) {
  if (value == "true" || value == "yes" || value == "on" || value == "1") return true;
  if (value == "false" || value == "no" || value == "off" || value == "0") return false;
  throw std::invalid_argument("is not true or false");
}

std::string formatBytes(std::uint64_t bytes) {
  const char* units[] = {"GiB", "MiB", "KiB"};
  const std::uint64_t scales[] = {std::uint64_t{1} << 30, std::uint64_t{1} << 20, std::uint64_t{1} << 10};
  for (int i = 0; i < 3; ++i)
    if (bytes >= scales[i] && bytes % scales[i] == 0) return std::to_string(bytes / scales[i]) + units[i];
  return std::to_string(bytes) + "B";
}

std::string formatDuration(std::chrono::milliseconds d) {
  const auto ms = d.count();
  if (ms % 60000 == 0 && ms != 0) return std::to_string(ms / 60000) + "min";
  if (ms % 1000 == 0) return std::to_string(ms / 1000) + "s";
  return std::to_string(ms) + "ms";
}

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

// "dir1:dir2" (as PATH is written): absolute directories only, since jobs run elsewhere.
std::vector<std::filesystem::path> parseDirectoryList(const std::string& value) {
  std::vector<std::filesystem::path> dirs;
  std::size_t begin = 0;
  while (begin <= value.size()) {
    const std::size_t end = std::min(value.find(':', begin), value.size());
    const std::string dir = trim(value.substr(begin, end - begin));
    if (!dir.empty()) {
      if (dir.front() != '/') throw std::invalid_argument("names '" + dir + "', which is not an absolute path");
      dirs.emplace_back(dir);
    }
    begin = end + 1;
  }
  return dirs;
}

// "a, b": host names (letters, digits, '-', '.').
std::vector<std::string> parseNameList(const std::string& value) {
  std::vector<std::string> names;
  std::stringstream in(value);
  for (std::string name; std::getline(in, name, ',');) {
    name = trim(name);
    if (name.empty()) continue;
    for (const char ch : name)
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '.')
        throw std::invalid_argument("names '" + name + "', which is not a host name");
    names.push_back(name);
  }
  return names;
}

std::string formatNameList(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

std::string formatDirectoryList(const std::vector<std::filesystem::path>& dirs) {
  std::string text;
  for (const auto& d : dirs) text += (text.empty() ? "" : ":") + d.string();
  return text;
}

struct Setting {
  const char* key;  // section.key
  std::function<void(ServerConfig&, const std::string&)> parse;
  std::function<std::string(const ServerConfig&)> format;
};

// A limit of the URDFs LoadModel accepts (ServiceOptions::urdf_limits).
Setting urdfLimitSetting(const char* key, std::uint64_t UrdfLimits::*field) {
  return {key, [field](ServerConfig& c, const std::string& v) { c.service.urdf_limits.*field = parseUnsigned(v, 1u << 30); },
          [field](const ServerConfig& c) { return std::to_string(c.service.urdf_limits.*field); }};
}

template <class T>
Setting unsignedSetting(const char* key, T ServiceOptions::*field, std::uint64_t max) {
  return {key, [field, max](ServerConfig& c, const std::string& v) { c.service.*field = static_cast<T>(parseUnsigned(v, max)); },
          [field](const ServerConfig& c) { return std::to_string(c.service.*field); }};
}

// A per-client limit of the transports' fair sharing (ServerConfig::limits).
Setting clientLimitSetting(const char* key, std::uint32_t ClientLimits::*field) {
  return {key, [field](ServerConfig& c, const std::string& v) {
            const std::uint64_t n = parseUnsigned(v, 1u << 20);
            if (n == 0) throw std::invalid_argument("must be at least 1");
            c.limits.*field = static_cast<std::uint32_t>(n);
          },
          [field](const ServerConfig& c) { return std::to_string(c.limits.*field); }};
}

const std::vector<Setting>& settings() {
  static const std::vector<Setting> table = {
      {"service.instance_id", [](ServerConfig& c, const std::string& v) { c.service.instance_id = v; },
       [](const ServerConfig& c) { return quoted(c.service.instance_id); }},
      unsignedSetting("service.request_threads", &ServiceOptions::request_threads, 256),
      unsignedSetting("service.request_queue", &ServiceOptions::request_queue_capacity, 1u << 20),
      unsignedSetting("service.batch_threads", &ServiceOptions::batch_threads, 256),
      unsignedSetting("service.background_nice", &ServiceOptions::background_nice, 19),
      unsignedSetting("service.max_batch_knots", &ServiceOptions::max_batch_knots, 100'000'000),
      unsignedSetting("service.max_models", &ServiceOptions::max_models, 1u << 20),
      unsignedSetting("service.max_functions", &ServiceOptions::max_functions, 1u << 20),
      {"service.max_urdf", [](ServerConfig& c, const std::string& v) { c.service.max_urdf_bytes = parseBytes(v); },
       [](const ServerConfig& c) { return formatBytes(c.service.max_urdf_bytes); }},
      urdfLimitSetting("service.max_urdf_depth", &UrdfLimits::max_depth),
      urdfLimitSetting("service.max_urdf_elements", &UrdfLimits::max_elements),
      urdfLimitSetting("service.max_urdf_links", &UrdfLimits::max_links),
      urdfLimitSetting("service.max_urdf_joints", &UrdfLimits::max_joints),
      urdfLimitSetting("service.max_urdf_name_length", &UrdfLimits::max_name_length),
      urdfLimitSetting("service.max_urdf_attribute_length", &UrdfLimits::max_attribute_length),
      {"service.max_spec", [](ServerConfig& c, const std::string& v) { c.service.max_spec_bytes = parseBytes(v); },
       [](const ServerConfig& c) { return formatBytes(c.service.max_spec_bytes); }},
      clientLimitSetting("limits.max_queued_requests_per_client", &ClientLimits::max_queued_requests_per_client),
      clientLimitSetting("limits.max_running_requests_per_client", &ClientLimits::max_running_requests_per_client),
      clientLimitSetting("limits.error_replies_per_second", &ClientLimits::error_replies_per_second),
      // Each session is an iceoryx server port and a WaitSet attachment (256 per WaitSet).
      {"limits.max_shm_sessions",
       [](ServerConfig& c, const std::string& v) {
         const std::uint64_t n = parseUnsigned(v, 250);
         if (n == 0) throw std::invalid_argument("must be at least 1");
         c.limits.max_shm_sessions = static_cast<std::uint32_t>(n);
       },
       [](const ServerConfig& c) { return std::to_string(c.limits.max_shm_sessions); }},
      unsignedSetting("limits.max_models_per_client", &ServiceOptions::max_models_per_client, 1u << 20),
      unsignedSetting("limits.max_functions_per_client", &ServiceOptions::max_functions_per_client, 1u << 20),
      unsignedSetting("build.workers", &ServiceOptions::build_workers, 256),
      {"build.compile", [](ServerConfig& c, const std::string& v) { c.service.compile = parseBool(v); },
       [](const ServerConfig& c) { return std::string(c.service.compile ? "true" : "false"); }},
      {"build.compiler", [](ServerConfig& c, const std::string& v) { c.service.compiler = v; },
       [](const ServerConfig& c) { return quoted(c.service.compiler); }},
      {"build.worker_executable", [](ServerConfig& c, const std::string& v) { c.service.worker_executable = v; },
       [](const ServerConfig& c) { return quoted(c.service.worker_executable); }},
      {"build.timeout", [](ServerConfig& c, const std::string& v) { c.service.build_timeout = parseDuration(v); },
       [](const ServerConfig& c) { return formatDuration(c.service.build_timeout); }},
      {"build.memory_limit",
       [](ServerConfig& c, const std::string& v) { c.service.compiler_memory_limit_bytes = parseBytes(v); },
       [](const ServerConfig& c) { return formatBytes(c.service.compiler_memory_limit_bytes); }},
      unsignedSetting("jobs.workers", &ServiceOptions::job_workers, 256),
      {"jobs.timeout", [](ServerConfig& c, const std::string& v) { c.service.job_timeout = parseDuration(v); },
       [](const ServerConfig& c) { return formatDuration(c.service.job_timeout); }},
      {"jobs.memory_limit", [](ServerConfig& c, const std::string& v) { c.service.job_memory_limit_bytes = parseBytes(v); },
       [](const ServerConfig& c) { return formatBytes(c.service.job_memory_limit_bytes); }},
      {"jobs.data_dirs", [](ServerConfig& c, const std::string& v) { c.service.job_data_dirs = parseDirectoryList(v); },
       [](const ServerConfig& c) { return quoted(formatDirectoryList(c.service.job_data_dirs)); }},
      {"cache.dir", [](ServerConfig& c, const std::string& v) { c.service.cache_dir = v; },
       [](const ServerConfig& c) { return quoted(c.service.cache_dir.string()); }},
      {"cache.budget", [](ServerConfig& c, const std::string& v) { c.service.cache_budget_bytes = parseBytes(v); },
       [](const ServerConfig& c) { return formatBytes(c.service.cache_budget_bytes); }},
      {"iceoryx.enabled", [](ServerConfig& c, const std::string& v) { c.shm.enabled = parseBool(v); },
       [](const ServerConfig& c) { return std::string(c.shm.enabled ? "true" : "false"); }},
      {"iceoryx.service", [](ServerConfig& c, const std::string& v) { c.shm.service = v; },
       [](const ServerConfig& c) { return quoted(c.shm.service); }},
      {"iceoryx.roudi",
       [](ServerConfig& c, const std::string& v) {
         if (v != "auto" && v != "external" && v != "embedded" && v != "detached")
           throw std::invalid_argument("is not one of auto, external, embedded, detached");
         c.shm.roudi = v;
       },
       [](const ServerConfig& c) { return c.shm.roudi; }},
      {"dds.enabled", [](ServerConfig& c, const std::string& v) { c.dds.enabled = parseBool(v); },
       [](const ServerConfig& c) { return std::string(c.dds.enabled ? "true" : "false"); }},
      {"dds.domain",
       [](ServerConfig& c, const std::string& v) {
         c.dds.domain = v == "default" ? -1 : static_cast<std::int32_t>(parseUnsigned(v, 232));
       },
       [](const ServerConfig& c) { return c.dds.domain < 0 ? std::string("default") : std::to_string(c.dds.domain); }},
      {"dds.service", [](ServerConfig& c, const std::string& v) { c.dds.service = v; },
       [](const ServerConfig& c) { return quoted(c.dds.service); }},
      {"dds.max_sample", [](ServerConfig& c, const std::string& v) { c.dds.max_sample_bytes = parseBytes(v); },
       [](const ServerConfig& c) { return formatBytes(c.dds.max_sample_bytes); }},
      {"dds.security", [](ServerConfig& c, const std::string& v) { c.dds.security = v; },
       [](const ServerConfig& c) { return quoted(c.dds.security); }},
      {"dds.security_identity", [](ServerConfig& c, const std::string& v) { c.dds.security_identity = v; },
       [](const ServerConfig& c) { return quoted(c.dds.security_identity); }},
      {"dds.allow_unauthenticated",
       [](ServerConfig& c, const std::string& v) { c.dds.allow_unauthenticated = parseBool(v); },
       [](const ServerConfig& c) { return std::string(c.dds.allow_unauthenticated ? "true" : "false"); }},
      {"http.enabled", [](ServerConfig& c, const std::string& v) { c.http.enabled = parseBool(v); },
       [](const ServerConfig& c) { return std::string(c.http.enabled ? "true" : "false"); }},
      {"http.listen", [](ServerConfig& c, const std::string& v) { parseListenAddress(v, c.http); },
       [](const ServerConfig& c) { return quoted(c.http.host + ":" + std::to_string(c.http.port)); }},
      {"http.allowed_hosts", [](ServerConfig& c, const std::string& v) { c.http.allowed_hosts = parseNameList(v); },
       [](const ServerConfig& c) { return quoted(formatNameList(c.http.allowed_hosts)); }},
      {"log.level", [](ServerConfig& c, const std::string& v) { c.log_level = parseLogLevel(v); },
       [](const ServerConfig& c) { return std::string(toString(c.log_level)); }},
      {"log.format", [](ServerConfig& c, const std::string& v) { c.log_format = parseLogFormat(v); },
       [](const ServerConfig& c) { return std::string(c.log_format == LogFormat::Json ? "json" : "text"); }},
  };
  return table;
}

const Setting* findSetting(const std::string& key) {
  for (const Setting& s : settings())
    if (key == s.key) return &s;
  return nullptr;
}

std::string sectionOf(const std::string& key) { return key.substr(0, key.find('.')); }

}  // namespace

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
    std::string known;
    for (const Setting& s : settings()) known += std::string(known.empty() ? "" : ", ") + s.key;
    throw ConfigError(where + ": unknown setting '" + key + "' (known: " + known + ")");
  }
  std::string value = trim(raw_value);
  if (value.size() >= 2 && value.front() == '"' && value.back() == '"') value = value.substr(1, value.size() - 2);
  try {
    setting->parse(config, value);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(where + ": " + key + " = '" + value + "' " + e.what());
  }
}

void applyConfigText(ServerConfig& config, const std::string& text, const std::string& source) {
  std::istringstream in(text);
  std::string line, section;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = source + ":" + std::to_string(number);
    // A '#' outside quotes starts a comment.
    bool in_quotes = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
      if (line[i] == '"') in_quotes = !in_quotes;
      if (line[i] == '#' && !in_quotes) {
        line.resize(i);
        break;
      }
    }
    line = trim(line);
    if (line.empty()) continue;
    if (line.front() == '[') {
      if (line.back() != ']') throw ConfigError(where + ": section header '" + line + "' has no closing ']'");
      section = trim(line.substr(1, line.size() - 2));
      bool known = false;
      for (const Setting& s : settings()) known = known || sectionOf(s.key) == section;
      if (!known)
        throw ConfigError(where + ": unknown section [" + section +
                          "] (known: service, build, jobs, cache, iceoryx, dds, http, log)");
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) throw ConfigError(where + ": expected 'key = value', found '" + line + "'");
    if (section.empty()) throw ConfigError(where + ": '" + line + "' comes before any [section]");
    applySetting(config, section + "." + trim(line.substr(0, eq)), line.substr(eq + 1), where);
  }
}

void applyConfigFile(ServerConfig& config, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError("cannot read configuration file " + path + ": " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  applyConfigText(config, text.str(), path);
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
    out += key.substr(sec.size() + 1) + " = " + s.format(config) + "\n";
  }
  return out;
}

}  // namespace robodiff::server
