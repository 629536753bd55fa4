#include "output/warmup_progress.hpp"

#include "output/human_units.hpp"

#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <utility>

namespace robodiff::cli {

using workers::BuildState;
using workers::BuildStatus;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

ProgressStyle chooseProgressStyle(bool json) {
  if (json) return ProgressStyle::Json;
  const char* term = std::getenv("TERM");
  const bool smart_terminal = term && *term && std::strcmp(term, "dumb") != 0;
  return ::isatty(STDOUT_FILENO) && smart_terminal ? ProgressStyle::Terminal : ProgressStyle::Lines;
}

// ---- Helpers of the display -------------------------------------------------------

namespace {

// ANSI colour of a state on a terminal (SGR parameters).
const char* stateColour(BuildState state) {
  switch (state) {
    case BuildState::Done:
      return "32";  // green
    case BuildState::Cached:
      return "36";  // cyan
    case BuildState::Failed:
      return "1;31";  // bold red
    case BuildState::Building:
      return "33";  // yellow
    default:
      return "2";  // dim: pending, queued, waiting
  }
}

std::string padRight(std::string s, std::size_t width) {
  if (s.size() < width) s.append(width - s.size(), ' ');
  return s;
}

std::string padLeft(const std::string& s, std::size_t width) {
  return s.size() < width ? std::string(width - s.size(), ' ') + s : s;
}

std::string firstLine(const std::string& text) { return text.substr(0, text.find('\n')); }

std::string keyPrefix(const std::string& key) { return key.substr(0, 12); }

struct TerminalSize {
  std::size_t columns = 80, lines = 24;
};

TerminalSize terminalSize() {
  TerminalSize size;
  winsize ws{};
  if (::ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0) {
    if (ws.ws_col > 0) size.columns = ws.ws_col;
    if (ws.ws_row > 0) size.lines = ws.ws_row;
  }
  return size;
}

// True when stdout and stderr are the same file (e.g. both the terminal), so a message
// written to both would show twice.
bool stderrIsStdout() {
  struct stat out {
  }, err{};
  return ::fstat(STDOUT_FILENO, &out) == 0 && ::fstat(STDERR_FILENO, &err) == 0 && out.st_dev == err.st_dev &&
         out.st_ino == err.st_ino;
}

// Which rows a terminal frame shows when they do not all fit: those in progress, then
// failures, then the ones not started, then the finished ones; shown in target order.
std::vector<std::size_t> visibleRows(const std::vector<BuildStatus>& statuses, std::size_t room) {
  std::vector<std::size_t> order(statuses.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  if (statuses.size() <= room) return order;
  const auto rank = [&](std::size_t i) {
    const BuildState s = statuses[i].state;
    if (!workers::isFinal(s) && s != BuildState::Pending) return 0;
    if (s == BuildState::Failed) return 1;
    if (s == BuildState::Pending) return 2;
    return 3;
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return rank(a) < rank(b); });
  order.resize(room);
  std::sort(order.begin(), order.end());
  return order;
}

}  // namespace

// ---- WarmupProgress ---------------------------------------------------------------

WarmupProgress::WarmupProgress(ProgressStyle style, std::ostream& out, const std::vector<std::string>& spec_paths,
                               unsigned jobs)
    : style_(style), out_(out), jobs_(std::max(jobs, 1u)), started_(Clock::now()), rows_(spec_paths.size()) {
  for (std::size_t i = 0; i < rows_.size(); ++i) rows_[i].spec_path = spec_paths[i];
  colour_ = style_ == ProgressStyle::Terminal && std::getenv("NO_COLOR") == nullptr;
  if (style_ == ProgressStyle::Terminal) ticker_ = std::thread([this] { tick(); });
}

WarmupProgress::~WarmupProgress() { stopTicker(); }

void WarmupProgress::stopTicker() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  stop_signal_.notify_all();
  if (ticker_.joinable()) ticker_.join();
}

void WarmupProgress::update(std::size_t index, const BuildStatus& status) {
  std::lock_guard lock(mutex_);
  if (index >= rows_.size()) return;
  Row& row = rows_[index];
  row.status = status;
  row.received = Clock::now();
  row.seen = true;
  if (status.state == BuildState::Building && row.building_since < 0) row.building_since = status.seconds;
  if (status.state == BuildState::Done && row.build_seconds < 0)
    row.build_seconds = status.seconds - std::max(row.building_since, 0.0);
  if (style_ == ProgressStyle::Lines) printLine(row);
  if (style_ == ProgressStyle::Json) printJson(index, row);
  // Terminal: the ticker shows it within a tenth of a second.
}

void WarmupProgress::finish(const std::vector<BuildStatus>& finals) {
  stopTicker();
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < rows_.size() && i < finals.size(); ++i) {
    Row& row = rows_[i];
    row.status = finals[i];
    row.received = Clock::now();
    row.seen = true;
    if (style_ == ProgressStyle::Lines) printLine(row);
    if (style_ == ProgressStyle::Json) printJson(i, row);
  }
  if (style_ == ProgressStyle::Terminal) redraw(true);
  printSummary();
}

WarmupProgress::NameCounts WarmupProgress::countNames() const {
  NameCounts names;
  for (const Row& row : rows_) ++names[{row.status.robot, row.status.function}];
  return names;
}

std::string WarmupProgress::functionLabel(const Row& row, const NameCounts& names) const {
  const BuildStatus& s = row.status;
  const auto it = names.find({s.robot, s.function});
  const bool shared = it != names.end() && it->second > 1;
  return shared ? s.function + " (" + fs::path(row.spec_path).filename().string() + ")" : s.function;
}

double WarmupProgress::elapsed(const Row& row, Clock::time_point now) const {
  if (workers::isFinal(row.status.state)) return row.status.seconds;
  return row.status.seconds + std::chrono::duration<double>(now - row.received).count();
}

void WarmupProgress::printLine(Row& row) {
  const BuildStatus& s = row.status;
  const bool matters = s.state == BuildState::Waiting || s.state == BuildState::Building || workers::isFinal(s.state);
  if (!matters || s.state == row.printed) return;
  row.printed = s.state;
  // Columns as wide as the longest names: every name is known once the builder has read
  // the robots and specs, which it does before building anything.
  const NameCounts names = countNames();
  std::size_t robot_width = 0, function_width = 0;
  for (const Row& other : rows_) {
    robot_width = std::max(robot_width, other.status.robot.size());
    function_width = std::max(function_width, functionLabel(other, names).size());
  }
  std::string line = padRight(workers::toString(s.state), 8) + " " + padRight(s.robot, robot_width) + "  " +
                     padRight(functionLabel(row, names), function_width) + "  " + padLeft(formatFixed(s.seconds, 2), 6) +
                     " s";
  if (s.state == BuildState::Cached || s.state == BuildState::Done) {
    line += "  key " + keyPrefix(s.key);
    if (s.library_bytes > 0) line += "  " + formatBytes(s.library_bytes);
  } else if (!s.message.empty()) {
    line += "  " + firstLine(s.message);
  }
  out_ << line << "\n" << std::flush;
}

void WarmupProgress::printJson(std::size_t index, Row& row) {
  const BuildStatus& s = row.status;
  const std::string printed = std::string(workers::toString(s.state)) + "/" + s.stage;
  if (s.state == BuildState::Pending || printed == row.json_printed) return;
  row.json_printed = printed;
  const nlohmann::ordered_json event = {
      {"event", "state"},
      {"index", index},
      {"robot", s.robot},
      {"function", s.function},
      {"spec", row.spec_path},
      {"state", workers::toString(s.state)},
      {"stage", s.state == BuildState::Building ? s.stage : ""},
      {"seconds", std::round(s.seconds * 1000.0) / 1000.0},
      {"key", s.key},
      {"message", s.message},
      {"library_bytes", s.library_bytes},
  };
  out_ << event.dump() << "\n" << std::flush;
}

std::string WarmupProgress::barLine(std::size_t width) const {
  std::size_t ok = 0, failed = 0, remaining = 0, built = 0;
  double built_seconds = 0;
  for (const Row& row : rows_) {
    const BuildState s = row.status.state;
    if (s == BuildState::Cached || s == BuildState::Done) ++ok;
    if (s == BuildState::Failed) ++failed;
    if (!workers::isFinal(s)) ++remaining;
    if (s == BuildState::Done && row.build_seconds >= 0) {
      ++built;
      built_seconds += row.build_seconds;
    }
  }
  const std::size_t total = rows_.size();
  std::string text = std::to_string(ok) + "/" + std::to_string(total) + " done";
  if (failed > 0) text += ", " + std::to_string(failed) + " failed";
  text += ", " + formatClock(std::chrono::duration<double>(Clock::now() - started_).count()) + " elapsed";
  if (remaining > 0) {
    // The mean build time so far (from a worker taking the function to done) times the
    // functions left, shared by the workers.
    text += built == 0 ? ", ETA --"
                       : ", ETA " + formatClock(built_seconds / static_cast<double>(built) *
                                                static_cast<double>(remaining) / jobs_);
  }
  // The bar takes what the text leaves of the line, up to 30 columns; none below 5.
  const std::size_t room = width > text.size() + 3 ? width - text.size() - 3 : 0;
  const std::size_t bar_width = std::min<std::size_t>(room, 30);
  if (bar_width < 5) return text;
  const std::size_t filled = total == 0 ? bar_width : bar_width * (ok + failed) / total;
  return "[" + std::string(filled, '#') + std::string(bar_width - filled, '.') + "] " + text;
}

std::string WarmupProgress::renderFrame(bool final) const {
  const TerminalSize size = terminalSize();
  const std::size_t width = std::max<std::size_t>(size.columns, 21) - 1;  // never the last column: no wrapping
  const auto now = Clock::now();

  const NameCounts names = countNames();
  std::vector<BuildStatus> statuses;
  std::size_t robot_width = 5, function_width = 8;
  for (const Row& row : rows_) {
    statuses.push_back(row.status);
    robot_width = std::max(robot_width, std::min<std::size_t>(row.status.robot.size(), 24));
    function_width = std::max(function_width, std::min<std::size_t>(functionLabel(row, names).size(), 40));
  }
  // A frame must fit the screen to be redrawn in place; the final one is never redrawn.
  const std::size_t room = final ? rows_.size() : std::max<std::size_t>(size.lines, 5) - 3;
  const std::vector<std::size_t> shown = visibleRows(statuses, room);

  std::string frame;
  for (std::size_t i : shown) {
    const Row& row = rows_[i];
    const BuildStatus& s = row.status;
    std::string state = workers::toString(s.state);
    if (s.state == BuildState::Building && !s.stage.empty()) state += " (" + s.stage + ")";
    const std::string seconds = row.seen && s.state != BuildState::Pending ? formatFixed(elapsed(row, now), 1) + " s" : "";
    const std::string bytes = s.library_bytes > 0 && workers::isFinal(s.state) ? formatBytes(s.library_bytes) : "";
    std::string extra;
    if (s.state == BuildState::Failed || s.state == BuildState::Waiting) extra = firstLine(s.message);

    std::string line = "  " + padRight(s.robot.substr(0, robot_width), robot_width) + "  " +
                       padRight(functionLabel(row, names).substr(0, function_width), function_width) + "  ";
    const std::size_t state_begin = line.size();
    line += padRight(state, 18);
    const std::size_t state_end = state_begin + state.size();
    line += "  " + padLeft(seconds, 8) + "  " + padLeft(bytes, 10);
    if (!extra.empty()) line += "  " + extra;
    while (!line.empty() && line.back() == ' ') line.pop_back();
    if (line.size() > width) line.resize(width);
    if (colour_ && state_begin < line.size()) {
      const std::size_t end = std::min(state_end, line.size());
      line = line.substr(0, state_begin) + "\x1b[" + stateColour(s.state) + "m" +
             line.substr(state_begin, end - state_begin) + "\x1b[0m" + line.substr(end);
    }
    frame += line + "\n";
  }
  if (shown.size() < rows_.size()) frame += "  ... and " + std::to_string(rows_.size() - shown.size()) + " more\n";
  std::string bar = barLine(width);
  if (bar.size() > width) bar.resize(width);
  frame += bar + "\n";
  return frame;
}

void WarmupProgress::redraw(bool final) {
  const std::string frame = renderFrame(final);
  if (frame == last_frame_ && !final) return;
  last_frame_ = frame;
  std::string text;
  if (drawn_lines_ > 0) text += "\r\x1b[" + std::to_string(drawn_lines_) + "A";  // back to the frame's top
  std::size_t lines = 0;
  for (std::size_t begin = 0; begin < frame.size();) {
    const std::size_t end = frame.find('\n', begin);
    text += "\x1b[2K" + frame.substr(begin, end - begin) + "\n";  // each line cleared, then written
    begin = end + 1;
    ++lines;
  }
  text += "\x1b[J";  // and whatever a longer previous frame left below
  drawn_lines_ = lines;
  out_ << text << std::flush;
}

void WarmupProgress::tick() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    redraw(false);
    stop_signal_.wait_for(lock, std::chrono::milliseconds(100), [this] { return stopping_; });
  }
}

void WarmupProgress::printSummary() {
  std::size_t built = 0, cached = 0, failed = 0;
  nlohmann::ordered_json failures = nlohmann::ordered_json::array();
  std::string failure_text;
  const NameCounts names = countNames();
  for (const Row& row : rows_) {
    const BuildStatus& s = row.status;
    built += s.state == BuildState::Done;
    cached += s.state == BuildState::Cached;
    if (s.state != BuildState::Failed) continue;
    ++failed;
    failures.push_back({{"robot", s.robot},
                        {"function", s.function},
                        {"spec", row.spec_path},
                        {"key", s.key},
                        {"message", s.message}});
    // The whole reason, its continuation lines indented under the target.
    std::string reason = s.message.empty() ? "(no reason given)" : s.message;
    for (std::size_t at = reason.find('\n'); at != std::string::npos; at = reason.find('\n', at + 5))
      reason.replace(at, 1, "\n    ");
    failure_text += "  " + s.robot + "  " + functionLabel(row, names) + ": " + reason + "\n";
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - started_).count();
  const std::size_t total = rows_.size();

  if (style_ == ProgressStyle::Json) {
    out_ << nlohmann::ordered_json{{"event", "summary"},  {"functions", total},
                                   {"built", built},      {"cached", cached},
                                   {"failed", failed},    {"seconds", std::round(seconds * 10) / 10},
                                   {"failures", failures}}
                .dump()
         << "\n";
  } else {
    out_ << total << (total == 1 ? " function: " : " functions: ") << built << " built, " << cached << " cached, "
         << failed << " failed in " << formatFixed(seconds, 1) << " s\n";
    if (failed > 0) out_ << "\nFailed:\n" << failure_text;
  }
  out_ << std::flush;
  // Failures belong on stderr as well, unless they were just written there.
  if (failed > 0 && (style_ == ProgressStyle::Json || !stderrIsStdout()))
    std::cerr << "robodiff warmup: " << failed << (failed == 1 ? " function" : " functions") << " failed:\n"
              << failure_text << std::flush;
}

}  // namespace robodiff::cli
