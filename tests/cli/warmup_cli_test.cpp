// `robodiff warmup` as a user runs it: real processes (the CLI, its workers, the
// compiler), a real cache directory with its SQLite index, the output read back.
// The compiler is a wrapper script that logs each command line and then runs cc, so
// the tests count the builds: every build ends with exactly one command that makes the
// shared library (-shared), whether the library is split into parts or not.
// Specs are built at -O0 without -march=native, on arm7 only, to keep builds short.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/cache_workspace.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using nlohmann::json;
using testing::runCommand;
using testing::shellQuote;
using testing::TempDir;
namespace fs = std::filesystem;

using testing::cli;
using testing::countOf;

fs::path arm7Urdf() { return testing::sourceDir() / "examples/robots/arm7.urdf"; }

// The shared workspace, with warmup commands and specs written as text.
struct Workspace : testing::CacheWorkspace {
  fs::path specText(const std::string& name, const std::string& text) const { return tmp.file(name + ".json", text); }

  std::string warmupCommand(const std::vector<fs::path>& specs, const fs::path& urdf = arm7Urdf(),
                            const std::string& extra = "") const {
    std::string command = "warmup --urdf " + shellQuote(urdf.string()) + " --spec";
    for (const fs::path& s : specs) command.append(" ").append(shellQuote(s.string()));
    return cli(command + " --cache " + shellQuote(cache.string()) + " --compiler " + shellQuote(cc.string()) +
               " --jobs 2 " + extra);
  }
  testing::ProcessResult warmup(const std::vector<fs::path>& specs, const fs::path& urdf = arm7Urdf(),
                                const std::string& extra = "") const {
    return runCommand(warmupCommand(specs, urdf, extra));
  }

  json entries() const {
    testing::ProcessResult r = runCommand(cli("cache ls --json --cache " + shellQuote(cache.string())));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? json::parse(r.out) : json::array();
  }
};

// The lines of `text` that start with `state` (non-terminal output: one per change).
std::vector<std::string> linesStartingWith(const std::string& text, const std::string& state) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(state + " ", 0) == 0) lines.push_back(line);
  return lines;
}

TEST(WarmupCli, BuildsEachPairOnceThenServesThemFromTheCache) {
  Workspace w;
  const std::vector<fs::path> specs = {w.spec("rnea_jacobian"), w.spec("crba")};
  testing::ProcessResult r = w.warmup(specs);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(linesStartingWith(r.out, "building").size(), 2u) << r.out;
  ASSERT_EQ(linesStartingWith(r.out, "done").size(), 2u) << r.out;
  for (const std::string& line : linesStartingWith(r.out, "done")) {
    EXPECT_NE(line.find("arm7"), std::string::npos) << line;
    EXPECT_NE(line.find(" s  key "), std::string::npos) << line;
  }
  EXPECT_NE(r.out.find("2 functions: 2 built, 0 cached, 0 failed in "), std::string::npos) << r.out;
  EXPECT_EQ(w.builds(), 2u);

  const json entries = w.entries();
  ASSERT_EQ(entries.size(), 2u) << entries.dump(2);
  std::vector<std::string> functions;
  for (const json& e : entries) {
    EXPECT_EQ(e["state"], "ready") << e;
    EXPECT_EQ(e["robot"], "arm7") << e;
    EXPECT_EQ(e["key"].get<std::string>().size(), 64u) << e;
    EXPECT_GT(e["library_bytes"].get<std::uint64_t>(), 0u) << e;
    functions.push_back(e["function"]);
  }
  std::sort(functions.begin(), functions.end());
  EXPECT_EQ(functions, (std::vector<std::string>{"crba", "rnea"}));

  // Again: both cached (their hashes checked), the compiler never asked to build.
  r = w.warmup(specs);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(linesStartingWith(r.out, "cached").size(), 2u) << r.out;
  EXPECT_TRUE(linesStartingWith(r.out, "building").empty()) << r.out;
  EXPECT_NE(r.out.find("2 functions: 0 built, 2 cached, 0 failed in "), std::string::npos) << r.out;
  EXPECT_EQ(w.builds(), 2u);

  // --json: one object per line; states, then the summary.
  r = w.warmup(specs, arm7Urdf(), "--json");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  std::vector<json> events;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) events.push_back(json::parse(line));
  ASSERT_EQ(events.size(), 3u) << r.out;
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(events[i]["event"], "state");
    EXPECT_EQ(events[i]["state"], "cached");
    EXPECT_EQ(events[i]["robot"], "arm7");
    EXPECT_EQ(events[i]["key"].get<std::string>().size(), 64u);
  }
  EXPECT_EQ(events[2]["event"], "summary");
  EXPECT_EQ(events[2]["functions"], 2);
  EXPECT_EQ(events[2]["cached"], 2);
  EXPECT_EQ(events[2]["built"], 0);
  EXPECT_EQ(events[2]["failed"], 0);
}

TEST(WarmupCli, SameRobotWrittenDifferentlyHitsAndChangedMassMisses) {
  Workspace w;
  const std::vector<fs::path> specs = {w.spec("crba")};
  ASSERT_EQ(w.warmup(specs).exit_code, 0);
  ASSERT_EQ(w.builds(), 1u);

  // The same robot with other whitespace, a comment and self-closing tags spelt apart.
  std::string urdf = testing::readFile(arm7Urdf());
  const std::string declaration = "<?xml version=\"1.0\"?>\n";
  ASSERT_EQ(urdf.rfind(declaration, 0), 0u);
  std::string reformatted = declaration + "<!-- the same robot, laid out differently -->\n\n";
  for (char c : urdf.substr(declaration.size())) {
    if (c == '\n')
      reformatted += "\n\n    ";
    else
      reformatted += c;
  }
  std::size_t at = 0;
  while ((at = reformatted.find("/>", at)) != std::string::npos) {
    reformatted.replace(at, 2, "  />");
    at += 4;
  }
  testing::ProcessResult r = w.warmup(specs, w.tmp.file("arm7_reformatted.urdf", reformatted));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(linesStartingWith(r.out, "cached").size(), 1u) << r.out;
  EXPECT_EQ(w.builds(), 1u);

  // One link's mass changed: another robot, built anew.
  const std::string mass = "<mass value=\"2.3056640625\"/>";
  at = urdf.find(mass);
  ASSERT_NE(at, std::string::npos);
  urdf.replace(at, mass.size(), "<mass value=\"2.5\"/>");
  r = w.warmup(specs, w.tmp.file("arm7_heavier.urdf", urdf));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_EQ(linesStartingWith(r.out, "done").size(), 1u) << r.out;
  EXPECT_EQ(w.builds(), 2u);
  EXPECT_EQ(w.entries().size(), 2u);
}

// Two warmups started together on the same cache and the same keys build each key
// once: one builds it, the other waits for it and reports it cached.
TEST(WarmupCli, TwoProcessesStartedTogetherBuildEachKeyOnce) {
  Workspace w;
  const std::vector<fs::path> specs = {w.spec("rnea_jacobian"), w.spec("crba"), w.spec("nle")};
  const auto run = [&](const std::string& name) {
    const std::string out = shellQuote((w.tmp / (name + ".out")).string());
    const std::string err = shellQuote((w.tmp / (name + ".err")).string());
    const std::string status = shellQuote((w.tmp / (name + ".status")).string());
    return "(timeout 300 " + w.warmupCommand(specs) + " >" + out + " 2>" + err + "; echo $? >" + status + ")";
  };
  // The shell waits for both; `timeout` bounds each, should they deadlock.
  testing::ProcessResult r = runCommand(std::string("(") + run("a") + " & " + run("b") + " & wait)");
  ASSERT_EQ(r.exit_code, 0) << r.err;

  std::size_t done = 0, cached = 0;
  for (const std::string name : {"a", "b"}) {
    const std::string out = testing::readFile(w.tmp / (name + ".out"));
    EXPECT_EQ(testing::readFile(w.tmp / (name + ".status")), "0\n")
        << name << ":\n"
        << out << testing::readFile(w.tmp / (name + ".err"));
    done += linesStartingWith(out, "done").size();
    cached += linesStartingWith(out, "cached").size();
  }
  EXPECT_EQ(done, 3u);    // each key built by one process ...
  EXPECT_EQ(cached, 3u);  // ... and found ready by the other
  EXPECT_EQ(w.builds(), 3u) << testing::readFile(w.log);

  const json entries = w.entries();
  ASSERT_EQ(entries.size(), 3u) << entries.dump(2);
  for (const json& e : entries) EXPECT_EQ(e["state"], "ready") << e;
  r = runCommand(cli("cache verify --cache " + shellQuote(w.cache.string())));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("3 entries checked, no problems"), std::string::npos) << r.out;
}

TEST(WarmupCli, AFailedBuildIsListedWithItsReasonAndLeavesNoEntry) {
  Workspace w;
  const fs::path no_frame = w.specText(
      "fk_nowhere",
      R"({"function": "fk", "frame": "nowhere", "outputs": [{"kind": "value"}], "build": {"optimization": "O0", "march_native": false}})");
  testing::ProcessResult r = w.warmup({w.spec("crba"), no_frame});
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_EQ(linesStartingWith(r.out, "done").size(), 1u) << r.out;
  ASSERT_EQ(linesStartingWith(r.out, "failed").size(), 1u) << r.out;
  EXPECT_NE(r.out.find("1 built, 0 cached, 1 failed"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("nowhere"), std::string::npos) << r.out;  // the reason, in the list at the end
  EXPECT_NE(r.err.find("nowhere"), std::string::npos) << r.err;
  const json entries = w.entries();
  ASSERT_EQ(entries.size(), 1u) << entries.dump(2);
  EXPECT_EQ(entries[0]["function"], "crba");

  // A compiler that fails (it still tells its version: that is how the key knows it).
  Workspace failing;
  const fs::path bad_cc = failing.tmp.script(
      "failing-cc", "case \"$1\" in --version) exec cc --version;; esac\necho 'error: simulated' >&2\nexit 1\n");
  r = runCommand(cli("warmup --urdf " + shellQuote(arm7Urdf().string()) + " --spec " +
                     shellQuote(failing.spec("crba").string()) + " --cache " + shellQuote(failing.cache.string()) +
                     " --compiler " + shellQuote(bad_cc.string())));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_EQ(linesStartingWith(r.out, "failed").size(), 1u) << r.out;
  EXPECT_NE(r.out.find("error: simulated"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("error: simulated"), std::string::npos) << r.err;
  EXPECT_TRUE(failing.entries().empty());
  std::size_t artifacts = 0;
  if (fs::exists(failing.cache / "objects"))
    for (const auto& f : fs::recursive_directory_iterator(failing.cache / "objects")) artifacts += f.is_regular_file();
  EXPECT_EQ(artifacts, 0u);
}

// A library larger than the whole budget cannot be kept: a failure that says so.
TEST(WarmupCli, ABudgetTooSmallForTheLibraryFailsItWithTheReason) {
  Workspace w;
  testing::ProcessResult r = w.warmup({w.spec("crba")}, arm7Urdf(), "--budget 1K");
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  ASSERT_EQ(linesStartingWith(r.out, "failed").size(), 1u) << r.out;
  EXPECT_NE(r.err.find("budget"), std::string::npos) << r.err;
  EXPECT_TRUE(w.entries().empty());
}

TEST(WarmupCli, ArgumentErrorsAndUnsafeCacheDirectoriesAreRefused) {
  Workspace w;
  const fs::path spec = w.spec("crba");
  testing::ProcessResult r = w.warmup({spec}, w.tmp / "missing.urdf");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing.urdf: no such file"), std::string::npos) << r.err;

  r = w.warmup({w.specText("bad", R"({"function": "rnea", "outputs": [{"kind": "value", "wrt": 3}]})")});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("outputs[0]"), std::string::npos) << r.err;

  // A cache "directory" under a regular file cannot be created: the message names it.
  const fs::path file = w.tmp.file("file", "not a directory\n");
  r = runCommand(cli("warmup --urdf " + shellQuote(arm7Urdf().string()) + " --spec " + shellQuote(spec.string()) +
                     " --cache " + shellQuote((file / "cache").string())));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(file.string()), std::string::npos) << r.err;

  // Libraries are code that will run: a directory others may write to is refused.
  const fs::path shared = w.tmp / "shared-cache";
  fs::create_directory(shared);
  ASSERT_EQ(::chmod(shared.c_str(), 0777), 0);
  r = runCommand(cli("warmup --urdf " + shellQuote(arm7Urdf().string()) + " --spec " + shellQuote(spec.string()) +
                     " --cache " + shellQuote(shared.string())));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(shared.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("777"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(shared / "index.sqlite"));
  EXPECT_EQ(w.builds(), 0u);
}

// On a terminal (here a pseudo-terminal from script(1)) the functions are redrawn in
// place under a bar; the summary stays at the end.
TEST(WarmupCli, TerminalShowsABarAndRedrawsInPlace) {
  if (runCommand("command -v script").exit_code != 0) GTEST_SKIP() << "script(1) is not installed";
  Workspace w;
  const std::string command = w.warmupCommand({w.spec("crba")});
  testing::ProcessResult r = runCommand("TERM=xterm NO_COLOR=1 script -qefc " + shellQuote(command) + " /dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("\x1b[2K"), std::string::npos) << r.out;  // lines cleared and redrawn
  EXPECT_NE(r.out.find("] 1/1 done"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("[#"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("crba"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 function: 1 built, 0 cached, 0 failed"), std::string::npos) << r.out;
  EXPECT_EQ(linesStartingWith(r.out, "done").size(), 0u);  // not the plain lines
}

TEST(WarmupCli, HelpSaysWhatItDoesAndTheExitStatus) {
  testing::ProcessResult r = runCommand(cli("warmup --help"));
  EXPECT_EQ(r.exit_code, 0);
  for (const char* word :
       {"--urdf", "--spec", "--jobs", "--cache", "--compiler", "--timeout", "--json", "--budget", "Exit status: 0"})
    EXPECT_NE(r.out.find(word), std::string::npos) << word << " in\n" << r.out;
}

}  // namespace
}  // namespace robodiff
