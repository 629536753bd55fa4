// One log line per event, JSON or text: the event and its fields are formatted here
// (strings escaped by nlohmann::json), the time stamp and the writing are spdlog's.
#include "robodiff/server/log.hpp"

#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <spdlog/logger.h>
#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_sinks.h>

#include "robodiff/language/bounded_text.hpp"

namespace robodiff::server {
namespace {

// A JSON string literal; invalid UTF-8 replaced, never an exception.
void appendJsonString(std::string& out, std::string_view s) {
  out += nlohmann::json(std::string(s)).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// Text values are quoted when they hold spaces, quotes or '=' (logfmt's rule).
void appendTextValue(std::string& out, std::string_view s) {
  const bool quote = s.empty() || s.find_first_of(" \"=\t\n") != std::string_view::npos;
  if (quote)
    appendJsonString(out, s);
  else
    out += s;
}

void appendNumber(std::string& out, double v, bool json) {
  if (!std::isfinite(v)) {  // JSON has no NaN / inf: write them as strings
    const char* name = std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
    out += json ? "\"" + std::string(name) + "\"" : std::string(name);
    return;
  }
  out += fmt::format("{:.6g}", v);
}

void appendValue(std::string& out, const LogField& field, bool json) {
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::string_view>) {
          const bool cut = v.size() > kMaxLogValueBytes;
          const std::string bounded = cut ? language::boundedText(v, kMaxLogValueBytes) : std::string();
          const std::string_view shown = cut ? std::string_view(bounded) : v;
          json ? appendJsonString(out, shown) : appendTextValue(out, shown);
        } else if constexpr (std::is_same_v<T, bool>) {
          out += v ? "true" : "false";
        } else if constexpr (std::is_same_v<T, double>) {
          appendNumber(out, v, json);
        } else {
          out += std::to_string(v);
        }
      },
      field.value);
}

// What follows the time stamp: `"level":"info","event":"x","k":v...}` (JSON) or
// `info x k=v ...` (text).
std::string body(LogLevel level, std::string_view event, std::initializer_list<LogField> fields, bool json) {
  std::string line;
  line.reserve(160);
  if (json) {
    line += "\"level\":\"" + std::string(toString(level)) + "\",\"event\":";
    appendJsonString(line, event);
    for (const LogField& f : fields) {
      line += ',';
      appendJsonString(line, f.key);
      line += ':';
      appendValue(line, f, true);
    }
    return line + '}';
  }
  line += std::string(toString(level)) + ' ';
  line += event;
  for (const LogField& f : fields) {
    line += ' ';
    line += f.key;
    line += '=';
    appendValue(line, f, false);
  }
  return line;
}

// A body past the line limit (many long fields): one that keeps the event, the start of
// the body and its size, still one valid line of its format.
std::string cutBody(const std::string& body, LogLevel level, std::string_view event, bool json) {
  const std::string start = language::boundedText(body, kMaxLogLineBytes / 4);
  std::string out;
  if (json) {
    out = "\"level\":\"" + std::string(toString(level)) + "\",\"event\":";
    appendJsonString(out, event);
    out += ",\"line_bytes\":" + std::to_string(body.size()) + ",\"cut_line\":";
    appendJsonString(out, start);
    return out + '}';
  }
  out = std::string(toString(level)) + ' ';
  out += event;
  out += " line_bytes=" + std::to_string(body.size()) + " cut_line=";
  appendJsonString(out, start);
  return out;
}

// The time stamp in UTC with milliseconds: 2026-11-22T05:24:25.123Z.
std::unique_ptr<spdlog::formatter> formatterFor(LogFormat format) {
  const char* pattern = format == LogFormat::Json ? "{\"ts\":\"%Y-%m-%dT%H:%M:%S.%eZ\",%v" : "%Y-%m-%dT%H:%M:%S.%eZ %v";
  return std::make_unique<spdlog::pattern_formatter>(pattern, spdlog::pattern_time_type::utc);
}

}  // namespace

const char* toString(LogLevel level) {
  switch (level) {
    case LogLevel::Debug: return "debug";
    case LogLevel::Info: return "info";
    case LogLevel::Warn: return "warn";
    case LogLevel::Error: return "error";
  }
  return "info";
}

LogLevel parseLogLevel(std::string_view text) {
  if (text == "debug") return LogLevel::Debug;
  if (text == "info") return LogLevel::Info;
  if (text == "warn" || text == "warning") return LogLevel::Warn;
  if (text == "error") return LogLevel::Error;
  throw std::invalid_argument("log level '" + std::string(text) + "' is not one of debug, info, warn, error");
}

LogFormat parseLogFormat(std::string_view text) {
  if (text == "json") return LogFormat::Json;
  if (text == "text") return LogFormat::Text;
  throw std::invalid_argument("log format '" + std::string(text) + "' is not one of json, text");
}

Logger::Logger(std::FILE* out, LogLevel min_level, LogFormat format) : min_level_(min_level), format_(format) {
  if (out == nullptr) return;
  // stdout_sink_base: fwrite and fflush of each whole line, under spdlog's console mutex.
  auto sink = std::make_shared<spdlog::sinks::stdout_sink_base<spdlog::details::console_mutex>>(out);
  sink_logger_ = std::make_shared<spdlog::logger>("robodiffd", std::move(sink));
  sink_logger_->set_level(spdlog::level::trace);  // the level is filtered here, before formatting
  sink_logger_->set_formatter(formatterFor(format));
}

Logger::~Logger() = default;

void Logger::setFormat(LogFormat format) {
  format_ = format;
  if (sink_logger_) sink_logger_->set_formatter(formatterFor(format));
}

void Logger::log(LogLevel level, std::string_view event, std::initializer_list<LogField> fields) {
  if (!enabled(level) || !sink_logger_) return;
  const bool json = format_ == LogFormat::Json;
  std::string text = body(level, event, fields, json);
  if (text.size() + 40 > kMaxLogLineBytes) text = cutBody(text, level, event, json);  // 40: the time stamp
  sink_logger_->log(spdlog::level::info, std::string_view(text));
}

}  // namespace robodiff::server
