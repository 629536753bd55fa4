#include "support/process.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "support/test_paths.hpp"

namespace robodiff::testing {

std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

ProcessResult runCommand(const std::string& command_line) {
  namespace fs = std::filesystem;
  fs::path dir = fs::temp_directory_path() / ("robodiff-test-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fs::path out = dir / "stdout", err = dir / "stderr";
  std::string full = command_line + " >" + shellQuote(out.string()) + " 2>" + shellQuote(err.string()) + " </dev/null";
  int status = std::system(full.c_str());
  ProcessResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = readFile(out);
  r.err = readFile(err);
  fs::remove_all(dir);
  return r;
}

}  // namespace robodiff::testing
