// robodiffd.conf is TOML, read with toml++: each [section]'s keys are looked up in the
// settings table (config_settings.hpp) and their values checked against the key's kind
// before the table parses them. Every error names the file, line and column, the key and
// the value; a syntax error is toml++'s description at its position.
#include <toml++/toml.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "config_settings.hpp"
#include "config_values.hpp"
#include "server_config.hpp"

namespace robodiff::server {
namespace {

using config_values::closestName;
using config_values::joined;
using config_values::tomlString;
using config_values::trim;

std::string position(const std::string& source, const toml::source_position& at) {
  return source + ":" + std::to_string(at.line) + ":" + std::to_string(at.column);
}

// "a string", "an integer", ...: what a TOML value is, for errors.
std::string typeName(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a floating-point number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    default: return "a date or time";
  }
}

// The value as written in TOML ("many" quoted, 1.5, 1979-05-27; {...}, [...]), for errors.
std::string tomlText(const toml::node& node) {
  if (const auto* s = node.as_string()) return tomlString(s->get());
  if (node.is_table()) return "{...}";
  if (node.is_array()) return "[...]";
  std::ostringstream out;
  node.visit([&out](const auto& value) {
    if constexpr (toml::is_value<decltype(value)>) out << value;
  });
  return out.str();
}

// The text the settings table parses, when the TOML type suits the key's kind.
std::optional<std::string> valueText(const Setting& setting, const toml::node& node) {
  const bool string = node.is_string(), integer = node.is_integer();
  switch (setting.kind) {
    case ValueKind::Text:
      if (string) return node.as_string()->get();
      break;
    case ValueKind::Flag:
      if (node.is_boolean()) return node.as_boolean()->get() ? "true" : "false";
      break;
    case ValueKind::Count:
      if (integer) return std::to_string(node.as_integer()->get());
      break;
    case ValueKind::Size:
    case ValueKind::Duration:
    case ValueKind::DomainId:
      if (string) return node.as_string()->get();
      if (integer) return std::to_string(node.as_integer()->get());
      break;
  }
  return std::nullopt;
}

struct Entry {
  std::string section, key;
  const toml::key* key_node;
  const toml::node* value;
};

// A key outside every section, or a section that is not a table ([[service]], service = 1).
[[noreturn]] void rootKeyError(const std::string& source, const toml::key& key, const toml::node& value) {
  const std::string name(key.str());
  const std::string where = position(source, key.source().begin);
  const std::vector<std::string> sections = sectionNames();
  if (std::find(sections.begin(), sections.end(), name) != sections.end())
    throw ConfigError(where + ": " + name + " is " + typeName(value) + "; expected the section [" + name + "]" +
                      (value.is_array() ? " (written once, not [[" + name + "]])" : ""));
  std::string homes;
  for (const std::string& section : sections) {
    const std::vector<std::string> keys = keysOf(section);
    if (std::find(keys.begin(), keys.end(), name) != keys.end()) homes += (homes.empty() ? "" : ", ") + ("[" + section + "]");
  }
  throw ConfigError(where + ": " + name + " = " + tomlText(value) + " comes before any [section]" +
                    (homes.empty() ? "" : " (" + name + " is a key of " + homes + ")"));
}

// Every section's key-value pairs, in file order (toml++ tables iterate sorted by key).
std::vector<Entry> entriesInFileOrder(const toml::table& root, const std::string& source) {
  std::vector<Entry> entries;
  for (const auto& [section_key, section_node] : root) {
    const std::string section(section_key.str());
    const toml::table* table = section_node.as_table();
    if (table == nullptr) rootKeyError(source, section_key, section_node);
    const std::vector<std::string> sections = sectionNames();
    if (std::find(sections.begin(), sections.end(), section) == sections.end()) {
      const std::string closest = closestName(section, sections);
      throw ConfigError(position(source, section_key.source().begin) + ": unknown section [" + section + "]" +
                        (closest.empty() ? "" : " (did you mean [" + closest + "]?)") + "; known: " + joined(sections));
    }
    for (const auto& [key, value] : *table) entries.push_back({section, std::string(key.str()), &key, &value});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    const auto pa = a.key_node->source().begin, pb = b.key_node->source().begin;
    return pa.line != pb.line ? pa.line < pb.line : pa.column < pb.column;
  });
  return entries;
}

void applyEntry(ServerConfig& config, const Entry& entry, const std::string& source) {
  const std::string full_key = entry.section + "." + entry.key;
  const Setting* setting = findSetting(full_key);
  if (setting == nullptr) {
    const std::vector<std::string> keys = keysOf(entry.section);
    const std::string closest = closestName(entry.key, keys);
    throw ConfigError(position(source, entry.key_node->source().begin) + ": unknown setting '" + full_key + "'" +
                      (closest.empty() ? "" : " (did you mean '" + entry.section + "." + closest + "'?)") + "; [" +
                      entry.section + "] has: " + joined(keys));
  }
  const std::string where = position(source, entry.value->source().begin);
  const std::optional<std::string> text = valueText(*setting, *entry.value);
  if (!text)
    throw ConfigError(where + ": " + full_key + " = " + tomlText(*entry.value) + " is " + typeName(*entry.value) +
                      "; expected " + expectedValue(*setting));
  parseSettingValue(*setting, config, *text, where);
}

// For a syntax error on a line "key = value" whose value is unquoted: the likely fix
// (sizes, durations and names are strings in TOML; booleans are true / false).
std::string syntaxHint(const std::string& text, std::size_t line_number) {
  std::istringstream in(text);
  std::string line;
  for (std::size_t n = 0; n < line_number && std::getline(in, line);) ++n;
  const auto eq = line.find('=');
  if (eq == std::string::npos) return "";
  const std::string key = trim(line.substr(0, eq));
  std::string value = trim(line.substr(eq + 1));
  value = trim(value.substr(0, value.find('#')));
  if (key.empty() || value.empty() || std::strchr("\"'[{", value.front()) != nullptr) return "";
  if (value == "yes" || value == "no" || value == "on" || value == "off")
    return " (a flag is true or false: " + key + " = " + (value == "yes" || value == "on" ? "true" : "false") + ")";
  return " (sizes, durations and names are strings in TOML: " + key + " = " + tomlString(value) + ")";
}

}  // namespace

void applyConfigText(ServerConfig& config, const std::string& text, const std::string& source) {
  toml::table root;
  try {
    root = toml::parse(text, std::string(source));
  } catch (const toml::parse_error& e) {
    throw ConfigError(position(source, e.source().begin) + ": not valid TOML: " + std::string(e.description()) +
                      syntaxHint(text, e.source().begin.line));
  }
  for (const Entry& entry : entriesInFileOrder(root, source)) applyEntry(config, entry, source);
}

void applyConfigFile(ServerConfig& config, const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw ConfigError("cannot read configuration file " + path + ": it is a directory");
  std::ifstream in(path);
  if (!in) throw ConfigError("cannot read configuration file " + path + ": " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  applyConfigText(config, text.str(), path);
}

}  // namespace robodiff::server
