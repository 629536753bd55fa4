// The model's identity (canonicalHash) must not depend on how robodiff was compiled: the
// main build (-march=native by default) and core/model compiled again for generic x86-64
// (the helper model_hash_generic, core/model/CMakeLists.txt) must agree bit for bit on
// every robot, fixed and free-flyer. Before the loader's arithmetic moved to
// core/model/src/portable_geometry.cpp, Eigen's vectorised order and GCC's fused
// multiply-adds made them differ in the last bits of rotations and inertias.
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/process.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

namespace fs = std::filesystem;
using testing::runCommand;
using testing::shellQuote;

// Runs the generic build on `urdf`; `form`: the canonical form instead of the hash.
std::string portableHashGenericOutput(const fs::path& urdf, RootJoint root, bool form) {
#ifdef ROBODIFF_MODEL_HASH_GENERIC
  std::string command = shellQuote(ROBODIFF_MODEL_HASH_GENERIC);
  if (root == RootJoint::FreeFlyer) command += " --free-flyer";
  if (form) command += " --form";
  const testing::ProcessResult r = runCommand(command + " " + shellQuote(urdf.string()));
  EXPECT_EQ(r.exit_code, 0) << command << " failed on " << urdf << ": " << r.err;
  return r.out;
#else
  (void)urdf, (void)root, (void)form;
  return {};
#endif
}

// The first line where two canonical forms differ, for a readable failure.
std::string portableHashFirstDifference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb;
  for (int line = 1;; ++line) {
    const bool more_a = static_cast<bool>(std::getline(sa, la));
    const bool more_b = static_cast<bool>(std::getline(sb, lb));
    if (!more_a && !more_b) break;
    if (!more_a) la = "(end)";
    if (!more_b) lb = "(end)";
    if (la != lb) return "line " + std::to_string(line) + ":\n  main:    " + la + "\n  generic: " + lb;
  }
  return "(forms equal)";
}

void portableHashExpectSame(const fs::path& urdf) {
  for (RootJoint root : {RootJoint::Fixed, RootJoint::FreeFlyer}) {
    const char* root_name = root == RootJoint::FreeFlyer ? "free-flyer" : "fixed";
    const Model model = loadUrdfFile(urdf.string(), root);
    const std::string main_hash = canonicalHash(model);
    const std::string generic_hash = portableHashGenericOutput(urdf, root, false);
    ASSERT_EQ(generic_hash.size(), 65u) << urdf << " (" << root_name << "): not a hash: " << generic_hash;
    if (generic_hash.substr(0, 64) != main_hash) {
      ADD_FAILURE() << urdf.filename() << " (" << root_name << "): the main build's hash " << main_hash
                    << " differs from the generic x86-64 build's " << generic_hash.substr(0, 64) << "; first "
                    << portableHashFirstDifference(canonicalForm(model),
                                                   portableHashGenericOutput(urdf, root, true));
    }
  }
}

#ifdef ROBODIFF_MODEL_HASH_GENERIC
#define PORTABLE_HASH_REQUIRE_HELPER()
#else
#define PORTABLE_HASH_REQUIRE_HELPER() \
  GTEST_SKIP() << "model_hash_generic is built on x86-64 only (core/model/CMakeLists.txt)"
#endif

TEST(PortableHash, ExampleRobotsHashTheSameInTheGenericBuild) {
  PORTABLE_HASH_REQUIRE_HELPER();
  std::vector<fs::path> robots;
  for (const auto& entry : fs::directory_iterator(testing::sourceDir() / "examples" / "robots"))
    if (entry.path().extension() == ".urdf") robots.push_back(entry.path());
  ASSERT_GE(robots.size(), 3u) << "examples/robots should hold arm7, humanoid and quadruped";
  for (const fs::path& urdf : robots) portableHashExpectSame(urdf);
}

TEST(PortableHash, PublicRobotsHashTheSameInTheGenericBuild) {
  PORTABLE_HASH_REQUIRE_HELPER();
  ROBODIFF_REQUIRE_SHARED(shared);
  std::vector<fs::path> robots;
  for (const auto& entry : fs::directory_iterator(shared / "robots"))
    if (entry.path().extension() == ".urdf") robots.push_back(entry.path());
  ASSERT_FALSE(robots.empty()) << "no URDF in " << shared / "robots";
  for (const fs::path& urdf : robots) portableHashExpectSame(urdf);
}

}  // namespace
}  // namespace robodiff
