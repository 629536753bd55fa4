// Runs a command line in a shell and captures its exit status, stdout and stderr.
#pragma once

#include <string>

namespace robodiff::testing {

struct ProcessResult {
  int exit_code = -1;
  std::string out, err;
};

ProcessResult runCommand(const std::string& command_line);

// Quotes s for a POSIX shell.
std::string shellQuote(const std::string& s);

}  // namespace robodiff::testing
