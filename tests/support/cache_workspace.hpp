// What the CLI tests of the cache need: a cache directory in a TempDir, a compiler that
// logs its command lines (to count builds), example specs built at -O0 for the generic
// target, and the `robodiff` command line.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

// `robodiff ARGS`, quoted for the shell.
inline std::string cli(const std::string& args) { return shellQuote(cliPath().string()) + " " + args; }

inline std::size_t countOf(const std::string& text, const std::string& word) {
  std::size_t n = 0;
  for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + word.size())) ++n;
  return n;
}

struct CacheWorkspace {
  TempDir tmp;
  std::filesystem::path cache = tmp / "cache";
  std::filesystem::path log = tmp / "cc.log";
  std::filesystem::path cc = tmp.script("logging-cc", "echo \"$*\" >> " + shellQuote(log.string()) + "\nexec cc \"$@\"\n");

  // The example spec `example`, built at -O0 for the generic target.
  std::filesystem::path spec(const std::string& example) const {
    nlohmann::json spec = nlohmann::json::parse(readFile(sourceDir() / "examples/specs" / (example + ".json")));
    spec["build"] = {{"optimization", "O0"}, {"march_native", false}};
    return tmp.file(example + ".json", spec.dump());
  }

  // Libraries linked so far: one -shared command per build, split or not.
  std::size_t builds() const { return std::filesystem::exists(log) ? countOf(readFile(log), "-shared") : 0; }
};

}  // namespace robodiff::testing
