// `robodiff compute` and `robodiff make-robot` as a user runs them: real processes,
// JSON parsed back and compared with Pinocchio's values and with the library.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/json_matrix.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::cliPath;
using testing::matricesAgree;
using testing::runCommand;
using testing::shellQuote;
using testing::TempDir;
using testing::matrixOf;

namespace fs = std::filesystem;

// `robodiff compute --urdf URDF --state STATE ARGS`.
std::string computeWith(const fs::path& urdf, const fs::path& state, const std::string& args) {
  return shellQuote(cliPath().string()) + " compute --urdf " + shellQuote(urdf.string()) + " --state " +
         shellQuote(state.string()) + " " + args;
}

std::string compute(const fs::path& urdf, const std::string& function, const fs::path& state, const std::string& extra = "") {
  return computeWith(urdf, state, "--function " + function + " " + extra);
}

nlohmann::json stateJson(const testing::GoldenSample& s) {
  auto vec = [](const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
  return {{"q", vec(s.q)}, {"v", vec(s.v)}, {"a", vec(s.a)}, {"tau", vec(s.tau)}};
}

// Every function through the CLI against the golden values of one sample per robot.
TEST(ComputeCli, AgreesWithGoldenValues) {
  ROBODIFF_REQUIRE_SHARED(shared);
  TempDir tmp;
  for (const std::string name : {"panda", "talos_ff"}) {
    SCOPED_TRACE(name);
    testing::GoldenRobot g = testing::loadGolden(shared, name);
    const testing::GoldenSample& s = g.samples[3];
    fs::path state = tmp.file(name + ".json", stateJson(s).dump());
    const std::string base = g.free_flyer ? "--floating-base" : "";
    auto run = [&](const std::string& fn, const std::string& extra = "") {
      testing::ProcessResult r = runCommand(compute(g.urdf, fn, state, base + " " + extra));
      EXPECT_EQ(r.exit_code, 0) << r.err;
      nlohmann::json j = nlohmann::json::parse(r.out);
      EXPECT_EQ(j["function"], fn);
      EXPECT_EQ(j["nq"], g.nq);
      EXPECT_EQ(j["nv"], g.nv);
      return j["value"];
    };
    EXPECT_TRUE(matricesAgree(matrixOf(run("rnea")), s.tau));
    EXPECT_TRUE(matricesAgree(matrixOf(run("aba")), s.ddq));
    EXPECT_TRUE(matricesAgree(matrixOf(run("crba")), s.M));
    EXPECT_TRUE(matricesAgree(matrixOf(run("gravity")), s.gravity_torque));
    EXPECT_TRUE(matricesAgree(matrixOf(run("nle")), s.nle));
    EXPECT_TRUE(matricesAgree(matrixOf(run("regressor")), s.regressor));
    nlohmann::json fk = run("fk");
    EXPECT_EQ(fk.size(), s.frame_placements.size());
    for (const auto& [frame, placement] : s.frame_placements) {
      EXPECT_TRUE(matricesAgree(matrixOf(fk[frame]["translation"]), placement.translation)) << frame;
      EXPECT_TRUE(matricesAgree(matrixOf(fk[frame]["rotation"]), placement.rotation)) << frame;
    }
    for (const auto& [frame, jacobian] : s.ee_jacobian_local_world_aligned)
      EXPECT_TRUE(matricesAgree(matrixOf(run("jacobian", "--frame " + frame + " --reference LOCAL_WORLD_ALIGNED")), jacobian))
          << frame;
  }
}

// Self-contained: a robot written by make-robot, evaluated by compute, equals the library.
TEST(ComputeCli, MakeRobotThenComputeAgreesWithTheLibrary) {
  TempDir tmp;
  fs::path urdf = tmp.path() / "tree.urdf";
  testing::ProcessResult made =
      runCommand(shellQuote(cliPath().string()) + " make-robot --tree 2x3 --seed 4 --out " + shellQuote(urdf.string()));
  ASSERT_EQ(made.exit_code, 0) << made.err;
  Model model = loadUrdfFile(urdf.string(), RootJoint::FreeFlyer);
  Data<double> data(model);
  Eigen::VectorXd q = neutralConfiguration(model);
  q.head<3>() << 0.1, -0.2, 0.3;
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(model.nv, -1, 1), a = v.reverse();
  fs::path state = tmp.file("state.json", nlohmann::json{{"q", std::vector<double>(q.data(), q.data() + q.size())},
                                                         {"v", std::vector<double>(v.data(), v.data() + v.size())},
                                                         {"a", std::vector<double>(a.data(), a.data() + a.size())}}
                                              .dump());
  testing::ProcessResult r = runCommand(compute(urdf, "rnea", state, "--floating-base"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(matricesAgree(matrixOf(nlohmann::json::parse(r.out)["value"]), rnea(model, data, q, v, a), 1e-14));
  r = runCommand(compute(urdf, "com", state, "--floating-base"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json com = nlohmann::json::parse(r.out)["value"];
  EXPECT_TRUE(matricesAgree(matrixOf(com["com"]), centerOfMass(model, data, q), 1e-14));
  EXPECT_NEAR(com["mass"].get<double>(), data.mass, 1e-12);
  // The table format prints one labelled row per joint.
  r = runCommand(compute(urdf, "rnea", state, "--floating-base --format table"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const Joint& j : model.joints) EXPECT_NE(r.out.find(j.name), std::string::npos) << r.out;
}

// --random-state prints what it drew; given back with --state it gives the same numbers,
// for the direct path, a spec with derivatives, and a user function.
TEST(ComputeCli, ARandomStateIsPrintedAndReproducible) {
  TempDir tmp;
  const std::string robodiff = shellQuote(cliPath().string());
  const std::string arm7 = shellQuote((testing::sourceDir() / "examples/robots/arm7.urdf").string());
  const std::vector<std::string> cases = {
      "--function rnea", "--function aba --derivatives",
      "--spec " + shellQuote((testing::sourceDir() / "examples/specs/arm7_mpc_knot.json").string())};
  for (const std::string& what : cases) {
    testing::ProcessResult r = runCommand(robodiff + " compute --urdf " + arm7 + " " + what + " --random-state 11");
    ASSERT_EQ(r.exit_code, 0) << what << ": " << r.err;
    nlohmann::json seeded = nlohmann::json::parse(r.out);
    ASSERT_TRUE(seeded.contains("random_state")) << r.out;
    nlohmann::json drawn = seeded["random_state"];
    EXPECT_EQ(drawn["seed"], 11);
    drawn.erase("seed");
    EXPECT_FALSE(drawn.empty());
    const fs::path state = tmp.file("state.json", drawn.dump());
    r = runCommand(robodiff + " compute --urdf " + arm7 + " " + what + " --state " + shellQuote(state.string()));
    ASSERT_EQ(r.exit_code, 0) << what << ": " << r.err;
    nlohmann::json again = nlohmann::json::parse(r.out);
    seeded.erase("random_state");
    EXPECT_EQ(again, seeded) << what;
  }
}

struct BadCase {
  std::string label, state, args, expected_message;
};

TEST(ComputeCli, BadInputFailsWithAClearMessage) {
  TempDir tmp;
  fs::path urdf = tmp.path() / "arm.urdf";
  ASSERT_EQ(runCommand(shellQuote(cliPath().string()) + " make-robot --chain 3 --seed 1 --out " + shellQuote(urdf.string())).exit_code, 0);
  fs::path broken = tmp.file("broken.urdf", "<robot name='x'><link name='a'/>\n<joint name='j' type='revolute'>\n");
  const std::vector<BadCase> cases = {
      {"short q", R"({"q": [0.1, 0.2], "v": [0,0,0], "a": [0,0,0]})", "--function rnea", "\"q\" has 2 numbers, the model has nq = 3"},
      {"missing v", R"({"q": [0.1, 0.2, 0.3]})", "--function rnea", "no \"v\", needed by rnea"},
      {"not a number", R"({"q": [0.1, "x", 0.3]})", "--function gravity", "\"q\"[1] is \"x\", not a number"},
      {"invalid json", R"({"q": [0.1, )", "--function gravity", "not valid JSON: line 1, column 13: unexpected end of input"},
      {"unknown frame", R"({"q": [0.1, 0.2, 0.3]})", "--function jacobian --frame nowhere", "no frame named 'nowhere'"},
      {"jacobian without frame", R"({"q": [0.1, 0.2, 0.3]})", "--function jacobian", "--function jacobian needs --frame"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.label);
    fs::path state = tmp.file("state.json", c.state);
    testing::ProcessResult r = runCommand(computeWith(urdf, state, c.args));
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.err.find(c.expected_message), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  fs::path good = tmp.file("good.json", R"({"q": [0.1, 0.2, 0.3]})");
  testing::ProcessResult r = runCommand(compute(tmp.path() / "missing.urdf", "gravity", good));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("missing.urdf: cannot open URDF file"), std::string::npos) << r.err;
  r = runCommand(compute(urdf, "gravity", tmp.path() / "nostate.json"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nostate.json: cannot open state file"), std::string::npos) << r.err;
  r = runCommand(compute(broken, "gravity", good));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("broken.urdf:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("malformed XML"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace robodiff
