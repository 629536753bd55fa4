#pragma once
// The settings table behind server_config.hpp: one entry per key, which parses a value's
// text into ServerConfig and prints it back. Internal to robodiffd's configuration: the
// TOML file reader (config_file.cpp), --set and --print-config (server_config.cpp) all go
// through it.

#include <functional>
#include <string>
#include <vector>

#include "server_config.hpp"

namespace robodiff::server {

// What a key's value is, which decides the TOML types a file may give it and how
// --print-config writes it.
enum class ValueKind {
  Text,      // a TOML string
  Flag,      // a TOML boolean
  Count,     // a TOML integer
  Size,      // a string with a unit ("512KiB") or an integer: bytes
  Duration,  // a string with a unit ("30s") or an integer: seconds
  DomainId,  // an integer, or the string "default"
};

struct Setting {
  const char* key;  // section.key
  ValueKind kind;
  std::function<void(ServerConfig&, const std::string&)> parse;  // std::invalid_argument if bad
  std::function<std::string(const ServerConfig&)> format;        // the value's text, unquoted
};

const std::vector<Setting>& settings();
const Setting* findSetting(const std::string& key);

// "service.max_spec" -> "service"; the sections in file order.
std::string sectionOf(const std::string& key);
std::vector<std::string> sectionNames();
// The key names of one section ("request_threads", ...), in file order.
std::vector<std::string> keysOf(const std::string& section);

// What a file must give for this kind, e.g. "a whole number (e.g. workers = 2)".
std::string expectedValue(const Setting& setting);

// Parses `value` with the setting; a ConfigError "<where>: key = 'value' <what is wrong>"
// if it does not parse.
void parseSettingValue(const Setting& setting, ServerConfig& config, const std::string& value,
                       const std::string& where);

}  // namespace robodiff::server
