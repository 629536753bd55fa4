// The progress display of `robodiff warmup`, in three styles:
//   - Terminal: one line per function (robot, function, state, elapsed, size) redrawn in
//     place at most 10 times a second, under an overall bar with an ETA;
//   - Lines: one plain line per state change that matters (waiting, building, cached,
//     done, failed), for logs and pipes;
//   - Json: one JSON object per state change, then a summary object.
// Every style ends with a summary line (or object) and each failure with its reason.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <ostream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "robodiff/workers/cached_builder.hpp"

namespace robodiff::cli {

enum class ProgressStyle : std::uint8_t { Terminal, Lines, Json };

// Json when asked; Terminal when stdout is a terminal and TERM is set and not "dumb";
// Lines otherwise.
ProgressStyle chooseProgressStyle(bool json);

class WarmupProgress {
 public:
  // One target per spec path (target i was made from spec_paths[i]), built by `jobs`
  // workers (for the ETA). Terminal style starts a thread that redraws the display until
  // finish().
  WarmupProgress(ProgressStyle style, std::ostream& out, const std::vector<std::string>& spec_paths, unsigned jobs);
  ~WarmupProgress();
  WarmupProgress(const WarmupProgress&) = delete;
  WarmupProgress& operator=(const WarmupProgress&) = delete;

  // A target's new status (the CachedBuilder's listener). Thread-safe.
  void update(std::size_t index, const workers::BuildStatus& status);

  // Stops redrawing, shows the final statuses, the summary, and each failure with its
  // reason (also on stderr, unless stderr is the same file as `out`).
  void finish(const std::vector<workers::BuildStatus>& finals);

 private:
  struct Row {
    workers::BuildStatus status;
    std::string spec_path;
    std::chrono::steady_clock::time_point received;  // when `status` arrived
    bool seen = false;                               // any status arrived
    double building_since = -1;  // status.seconds when a worker took it (queue time excluded from the ETA)
    double build_seconds = -1;   // Done: from a worker taking it to done
    workers::BuildState printed = workers::BuildState::Pending;  // Lines: last state printed
    std::string json_printed;                                    // Json: last state/stage printed
  };

  void printLine(Row& row);                     // Lines style: when the state changed in a way that matters
  void printJson(std::size_t index, Row& row);  // Json style: when the state or stage changed
  std::string renderFrame(bool final) const;    // Terminal style: the lines, without cursor movement
  void redraw(bool final);
  void tick();  // Terminal style: the ticker thread's loop
  void stopTicker();
  double elapsed(const Row& row, std::chrono::steady_clock::time_point now) const;
  // The function's name, with its spec's file name when another function of the same
  // robot has the same name (rnea from rnea_jacobian.json and from rnea_hessian.json).
  using NameCounts = std::map<std::pair<std::string, std::string>, std::size_t>;  // (robot, function) -> targets
  NameCounts countNames() const;
  std::string functionLabel(const Row& row, const NameCounts& names) const;
  std::string barLine(std::size_t width) const;
  void printSummary();

  ProgressStyle style_;
  std::ostream& out_;
  unsigned jobs_;
  std::chrono::steady_clock::time_point started_;
  std::vector<Row> rows_;
  bool colour_ = false;

  mutable std::mutex mutex_;
  std::condition_variable stop_signal_;
  bool stopping_ = false;
  std::thread ticker_;
  std::size_t drawn_lines_ = 0;  // Terminal: lines of the last frame, to move back over
  std::string last_frame_;
};

}  // namespace robodiff::cli
