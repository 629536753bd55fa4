// Running compiler processes: several at once, each in its own process group under an
// address-space limit, all killed (with their children) when the deadline passes, their
// combined stdout/stderr kept, their peak memory measured.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace robodiff::codegen::detail {

struct ProcessLimits {
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  std::uint64_t address_space_bytes = 0;  // RLIMIT_AS of each process (inherited by its children); 0: none
  unsigned jobs = 1;                      // processes running at once
};

struct ProcessOutcome {
  enum class State : std::uint8_t {
    Exited,        // exit_code says how
    Signaled,      // killed by `signal` (not by us)
    TimedOut,      // killed at the deadline
    Cancelled,     // not run, or killed, because another process failed
    CannotStart,   // the program could not be executed: start_error says why
  };
  State state = State::Cancelled;
  int exit_code = -1;
  int signal = 0;
  std::string start_error;
  std::string output;               // stdout and stderr interleaved, the first 256 KiB
  std::uint64_t peak_rss_bytes = 0; // the process or its largest waited-for child
  double seconds = 0;

  bool ok() const { return state == State::Exited && exit_code == 0; }
};

// Runs every command (argv[0] a path or a program name looked up in PATH), at most
// limits.jobs at a time, in order. After the first failure no further command starts
// and the running ones are killed (Cancelled).
std::vector<ProcessOutcome> runProcesses(const std::vector<std::vector<std::string>>& commands,
                                         const ProcessLimits& limits);

// A command line as a person would type it (for messages).
std::string commandLine(const std::vector<std::string>& argv);

}  // namespace robodiff::codegen::detail
