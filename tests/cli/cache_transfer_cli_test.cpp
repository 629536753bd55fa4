// `robodiff keygen`, `robodiff cache export` and `robodiff cache import` as a user runs
// them: a build host's cache filled by `robodiff compute`, a bundle signed with a key
// from keygen, imported into a robot's empty cache, where `cache verify` passes and
// `compute` loads the imported library (a cache hit, no compile, the same numbers).
// Refusals exit 1, name the problem and leave the robot's cache empty.
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "support/cache_workspace.hpp"
#include "support/process.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using nlohmann::json;
using testing::cli;
using testing::runCommand;
using testing::shellQuote;
namespace fs = std::filesystem;

// A build host's cache (`cache`), a robot's (`robot`), keys and a bundle path.
struct TransferWorkspace : testing::CacheWorkspace {
  fs::path robot = tmp / "robot-cache";
  fs::path keys = tmp / "keys";
  fs::path bundle = tmp / "fleet.tar";

  testing::ProcessResult compute(const fs::path& spec, const fs::path& cache_dir) const {
    return runCommand(cli("compute --urdf " + shellQuote((testing::sourceDir() / "examples/robots/arm7.urdf").string()) +
                          " --spec " + shellQuote(spec.string()) +
                          " --derivatives --backend generated --random-state 5 --compiler " + shellQuote(cc.string()) +
                          " --cache " + shellQuote(cache_dir.string())));
  }
  testing::ProcessResult run(const std::string& args) const { return runCommand(cli(args)); }
  std::string q(const fs::path& p) const { return shellQuote(p.string()); }
};

json withoutCacheField(json j) {
  j.erase("cache");
  return j;
}

TEST(CacheTransferCli, ExportedEntriesImportVerifiedAndLoadOnTheRobot) {
  TransferWorkspace w;
  const fs::path spec = w.spec("rnea_jacobian");
  const testing::ProcessResult built = w.compute(spec, w.cache);
  ASSERT_EQ(built.exit_code, 0) << built.err;
  ASSERT_EQ(w.builds(), 1u);

  testing::ProcessResult r = w.run("keygen --out " + w.q(w.keys) + " --name build-host");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("key id "), std::string::npos) << r.out;
  r = w.run("cache export --all --sign " + w.q(w.keys / "build-host.key") + " --out " + w.q(w.bundle) + " --cache " +
            w.q(w.cache) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const json exported = json::parse(r.out);
  ASSERT_EQ(exported["entries"].size(), 1u);
  const std::string key = exported["entries"][0]["key"];

  r = w.run("cache import " + w.q(w.bundle) + " --trust " + w.q(w.keys / "build-host.pub") + " --cache " + w.q(w.robot));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("1 imported, 0 already present and intact, 0 refused"), std::string::npos) << r.out;

  r = w.run("cache verify --cache " + w.q(w.robot));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("1 entry checked, no problems"), std::string::npos) << r.out;
  r = w.run("cache ls --json --cache " + w.q(w.robot));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(json::parse(r.out).size(), 1u);
  EXPECT_EQ(json::parse(r.out)[0]["key"], key);

  // The robot computes with the imported library: found under the same key, not compiled.
  const testing::ProcessResult robot = w.compute(spec, w.robot);
  ASSERT_EQ(robot.exit_code, 0) << robot.err;
  EXPECT_EQ(json::parse(robot.out)["cache"], "hit");
  EXPECT_EQ(w.builds(), 1u) << "the robot compiled instead of loading the imported library";
  EXPECT_EQ(withoutCacheField(json::parse(robot.out)).dump(), withoutCacheField(json::parse(built.out)).dump());

  // A directory of trusted keys works too; the entry is there already.
  r = w.run("cache import " + w.q(w.bundle) + " --trust " + w.q(w.keys) + " --cache " + w.q(w.robot));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("0 imported, 1 already present and intact, 0 refused"), std::string::npos) << r.out;
}

TEST(CacheTransferCli, RefusalsExitNonZeroNameTheProblemAndLeaveNothing) {
  TransferWorkspace w;
  ASSERT_EQ(w.compute(w.spec("crba"), w.cache).exit_code, 0);
  ASSERT_EQ(w.run("keygen --out " + w.q(w.keys) + " --name build-host").exit_code, 0);
  ASSERT_EQ(w.run("keygen --out " + w.q(w.keys / "other") + " --name stranger").exit_code, 0);

  // A private key readable by others signs nothing.
  ::chmod((w.keys / "build-host.key").c_str(), 0644);
  testing::ProcessResult r = w.run("cache export --all --sign " + w.q(w.keys / "build-host.key") + " --out " +
                                   w.q(w.bundle) + " --cache " + w.q(w.cache));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("has mode 0644"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(w.bundle));
  ::chmod((w.keys / "build-host.key").c_str(), 0600);
  r = w.run("cache export --all --sign " + w.q(w.keys / "build-host.key") + " --out " + w.q(w.bundle) + " --cache " +
            w.q(w.cache));
  ASSERT_EQ(r.exit_code, 0) << r.err;

  // Signed by a key the robot does not trust: refused, exit 1, nothing filed.
  r = w.run("cache import " + w.q(w.bundle) + " --trust " + w.q(w.keys / "other" / "stranger.pub") + " --cache " +
            w.q(w.robot) + " --json");
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  const json report = json::parse(r.out);
  EXPECT_EQ(report["refused"], 1);
  EXPECT_NE(report["entries"][0]["problem"].get<std::string>().find("unknown key"), std::string::npos) << r.out;
  r = w.run("cache ls --json --cache " + w.q(w.robot));
  EXPECT_EQ(json::parse(r.out).size(), 0u) << r.out;
  EXPECT_TRUE(fs::is_empty(w.robot / "staging"));

  // keygen never overwrites a key.
  r = w.run("keygen --out " + w.q(w.keys) + " --name build-host");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("refusing to overwrite"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace robodiff
