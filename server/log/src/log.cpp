// One log line per event, JSON or text, written whole under a mutex.
#include "robodiff/server/log.hpp"

#include <chrono>
#include <cmath>
#include <ctime>
#include <stdexcept>

#include "robodiff/language/bounded_text.hpp"

namespace robodiff::server {
namespace {

// 2026-11-22T05:24:25.123Z
std::string utcTimestamp() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto millis =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1,
                tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(millis));
  return text;
}

void appendJsonString(std::string& out, std::string_view s) {
  out += '"';
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char escaped[8];
          std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          out += escaped;
        } else {
          out += c;
        }
    }
  }
  out += '"';
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
    if (json) out += '"';
    out += std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
    if (json) out += '"';
    return;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  out += text;
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

// A line past kMaxLogLineBytes (many long fields): one that keeps the event, the start
// of the line and its size, still one valid line of its format.
std::string cutLine(const std::string& line, const std::string& ts, LogLevel level, std::string_view event,
                    bool json) {
  const std::string start = language::boundedText(line, kMaxLogLineBytes / 4);
  std::string out;
  if (json) {
    out = "{\"ts\":\"" + ts + "\",\"level\":\"" + toString(level) + "\",\"event\":";
    appendJsonString(out, event);
    out += ",\"line_bytes\":" + std::to_string(line.size()) + ",\"cut_line\":";
    appendJsonString(out, start);
    return out + "}\n";
  }
  out = ts + ' ' + toString(level) + ' ';
  out += event;
  out += " line_bytes=" + std::to_string(line.size()) + " cut_line=";
  appendJsonString(out, start);
  return out + '\n';
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

Logger::Logger(std::FILE* out, LogLevel min_level, LogFormat format)
    : out_(out), min_level_(min_level), format_(format) {}

void Logger::log(LogLevel level, std::string_view event, std::initializer_list<LogField> fields) {
  if (!enabled(level) || out_ == nullptr) return;
  std::string line;
  line.reserve(160);
  const std::string ts = utcTimestamp();
  if (format_ == LogFormat::Json) {
    line += "{\"ts\":\"" + ts + "\",\"level\":\"" + toString(level) + "\",\"event\":";
    appendJsonString(line, event);
    for (const LogField& f : fields) {
      line += ',';
      appendJsonString(line, f.key);
      line += ':';
      appendValue(line, f, true);
    }
    line += "}\n";
  } else {
    line += ts + ' ' + toString(level) + ' ';
    line += event;
    for (const LogField& f : fields) {
      line += ' ';
      line += f.key;
      line += '=';
      appendValue(line, f, false);
    }
    line += '\n';
  }
  if (line.size() > kMaxLogLineBytes) line = cutLine(line, ts, level, event, format_ == LogFormat::Json);
  std::lock_guard lock(mutex_);
  std::fwrite(line.data(), 1, line.size(), out_);
  std::fflush(out_);
}

}  // namespace robodiff::server
