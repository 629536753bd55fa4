#pragma once
// Structured logs: one line per event on a stream (stderr by default), as JSON objects
// ({"ts":"2026-11-22T05:24:25.123Z","level":"info","event":"model_loaded","model_id":"...",...})
// or as text (2026-11-22T05:24:25.123Z info model_loaded model_id=... nq=7), through an
// spdlog logger (its sink writes each line whole under a mutex, and stamps the UTC time).
// Bounded: a string value past kMaxLogValueBytes is cut to a
// prefix and its size; a line still past kMaxLogLineBytes is replaced by one that keeps
// its start (as the "cut_line" string) and its size.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <variant>

namespace spdlog {
class logger;
}

namespace robodiff::server {

enum class LogLevel { Debug, Info, Warn, Error };
inline constexpr std::size_t kMaxLogValueBytes = 2048;
inline constexpr std::size_t kMaxLogLineBytes = 8192;
enum class LogFormat { Json, Text };
const char* toString(LogLevel level);
// "debug" | "info" | "warn" | "error" ; throws std::invalid_argument naming the value.
LogLevel parseLogLevel(std::string_view text);
// "json" | "text"
LogFormat parseLogFormat(std::string_view text);

struct LogField {
  std::string_view key;
  std::variant<std::string_view, std::int64_t, std::uint64_t, double, bool> value;
  LogField(std::string_view k, std::string_view v) : key(k), value(v) {}
  LogField(std::string_view k, const std::string& v) : key(k), value(std::string_view(v)) {}
  LogField(std::string_view k, const char* v) : key(k), value(std::string_view(v)) {}
  LogField(std::string_view k, int v) : key(k), value(std::int64_t{v}) {}
  LogField(std::string_view k, long v) : key(k), value(std::int64_t{v}) {}
  LogField(std::string_view k, long long v) : key(k), value(std::int64_t{v}) {}
  LogField(std::string_view k, unsigned v) : key(k), value(std::uint64_t{v}) {}
  LogField(std::string_view k, unsigned long v) : key(k), value(std::uint64_t{v}) {}
  LogField(std::string_view k, unsigned long long v) : key(k), value(std::uint64_t{v}) {}
  LogField(std::string_view k, double v) : key(k), value(v) {}
  LogField(std::string_view k, bool v) : key(k), value(v) {}
};

class Logger {
 public:
  explicit Logger(std::FILE* out = stderr, LogLevel min_level = LogLevel::Info, LogFormat format = LogFormat::Json);
  ~Logger();
  Logger(const Logger&) = delete;
  Logger& operator=(const Logger&) = delete;

  void setLevel(LogLevel level) { min_level_ = level; }
  void setFormat(LogFormat format);
  bool enabled(LogLevel level) const { return level >= min_level_; }

  void log(LogLevel level, std::string_view event, std::initializer_list<LogField> fields = {});
  void debug(std::string_view event, std::initializer_list<LogField> fields = {}) { log(LogLevel::Debug, event, fields); }
  void info(std::string_view event, std::initializer_list<LogField> fields = {}) { log(LogLevel::Info, event, fields); }
  void warn(std::string_view event, std::initializer_list<LogField> fields = {}) { log(LogLevel::Warn, event, fields); }
  void error(std::string_view event, std::initializer_list<LogField> fields = {}) { log(LogLevel::Error, event, fields); }

 private:
  std::shared_ptr<spdlog::logger> sink_logger_;  // null when out was null
  LogLevel min_level_;
  LogFormat format_;
};

}  // namespace robodiff::server
