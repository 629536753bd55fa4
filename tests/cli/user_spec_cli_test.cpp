// User specs ("inputs" / "define" / "outputs") through the CLI as a user runs it: compute
// reading inputs by name and printing one key per output, checked against the CLI's own
// model functions combined by hand; generate and check (per-output errors, exit status 2
// when the compiled code is wrong); clear errors for a bad state file.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "support/golden.hpp"
#include "support/json_matrix.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using nlohmann::json;
using testing::matricesAgree;
using testing::matrixOf;
using testing::runCommand;
using testing::shellQuote;
using testing::TempDir;

namespace fs = std::filesystem;

// A semi-implicit Euler step and a tool-position cost on arm7, built at -O0 for the
// generic target (short compiles).
constexpr const char* kUserSpec = R"js({
  "description": "Semi-implicit Euler step and a tool-position cost", "name": "euler_step",
  "inputs": {"q": "configuration", "v": "nv", "u": "nv", "target": 3, "dt": {"fixed": [0.01]}},
  "define": {"v_next": "v + dt * aba(q, v, u)", "q_next": "integrate(q, dt * v_next)",
             "cost": "sumsq(frame_position(q, 'tool') - target)"},
  "outputs": [
    {"name": "q_next", "kind": "value", "of": "q_next"},
    {"name": "v_next", "kind": "value", "of": "v_next"},
    {"name": "dv_next", "kind": "jacobian", "of": "v_next", "wrt": ["q", "v", "u"]},
    {"name": "cost", "kind": "value", "of": "cost"},
    {"name": "grad", "kind": "gradient", "of": "cost", "wrt": ["q", "target"]},
    {"name": "hess", "kind": "hessian", "of": "cost", "wrt": ["q"], "layout": "sparse"}],
  "build": {"optimization": "O0", "march_native": false}})js";

constexpr double kDt = 0.01;
const std::string kQ = "[0.1, -0.4, 0.7, -1.0, 0.3, 0.5, -0.2]", kV = "[0.5, 0.1, -0.3, 0.2, 0.9, -0.6, 0.4]",
                  kU = "[1.0, -2.0, 0.5, 0.3, -0.1, 0.2, 0.05]", kTarget = "[0.3, 0.1, 0.6]";

std::string runCli(const std::string& args) { return shellQuote(testing::cliPath().string()) + " " + args; }

std::string arm7Path() {
  return "--urdf " + shellQuote((testing::sourceDir() / "examples/robots/arm7.urdf").string());
}

json parsedJson(const std::string& command) {
  const testing::ProcessResult r = runCommand(command);
  EXPECT_EQ(r.exit_code, 0) << command << "\n" << r.err;
  return r.exit_code == 0 ? json::parse(r.out) : json::object();
}

class UserSpecCli : public ::testing::Test {
 protected:
  // `robodiff compute` of the user spec at the state file.
  json computeUser(const std::string& extra = "") const {
    return parsedJson(runCli("compute " + arm7Path() + " --spec " + shellQuote(spec_.string()) + " --state " +
                      shellQuote(state_.string()) + " " + extra));
  }
  // `robodiff compute --function FN` at the same q, v (and tau = u).
  json computeFunction(const std::string& function) const {
    return parsedJson(runCli("compute " + arm7Path() + " --state " + shellQuote(model_state_.string()) + " --function " +
                      function));
  }

  TempDir tmp_;
  fs::path spec_ = tmp_.file("euler.json", kUserSpec);
  fs::path state_ =
      tmp_.file("state.json", R"({"q": )" + kQ + R"(, "v": )" + kV + R"(, "u": )" + kU + R"(, "target": )" + kTarget +
                                  R"(, "note": "ignored"})");
  fs::path model_state_ = tmp_.file("model_state.json", R"({"q": )" + kQ + R"(, "v": )" + kV + R"(, "tau": )" + kU + "}");
  Eigen::VectorXd q_ = matrixOf(json::parse(kQ)), v_ = matrixOf(json::parse(kV));
  Eigen::VectorXd target_ = matrixOf(json::parse(kTarget));
};

TEST_F(UserSpecCli, ComputeStepMatchesAbaCombinedByHand) {
  const json j = computeUser();
  EXPECT_EQ(j["function"], "euler_step");
  EXPECT_EQ(j["backend"], "interpreted");  // the default for a user spec
  for (const char* key : {"q_next", "v_next", "dv_next", "cost", "grad", "hess"}) EXPECT_TRUE(j.contains(key)) << key;

  // v_next = v + dt aba(q, v, u); q_next = q + dt v_next on revolute joints.
  const Eigen::VectorXd ddq = matrixOf(computeFunction("aba")["value"]);
  const Eigen::VectorXd v_next = v_ + kDt * ddq;
  EXPECT_TRUE(matricesAgree(matrixOf(j["v_next"]), v_next, 1e-12));
  EXPECT_TRUE(matricesAgree(matrixOf(j["q_next"]), q_ + kDt * v_next, 1e-12));

  // dv_next = [dt daba/dq, I + dt daba/dv, dt daba/du].
  const json aba = parsedJson(runCli("compute " + arm7Path() + " --state " + shellQuote(model_state_.string()) +
                              " --function aba --derivatives --backend interpreted"));
  Eigen::MatrixXd expected = kDt * matrixOf(aba["jacobian"]);
  expected.block(0, 7, 7, 7) += Eigen::MatrixXd::Identity(7, 7);
  const Eigen::MatrixXd dv_next = matrixOf(j["dv_next"]);
  ASSERT_EQ(dv_next.rows(), 7);
  ASSERT_EQ(dv_next.cols(), 21);
  EXPECT_TRUE(matricesAgree(dv_next, expected, 1e-10));
}

TEST_F(UserSpecCli, ComputeCostMatchesForwardKinematicsAndTheFrameJacobian) {
  const json j = computeUser();
  const Eigen::Vector3d p = matrixOf(computeFunction("fk --frame tool")["value"]["tool"]["translation"]);
  const Eigen::Vector3d e = p - target_;
  ASSERT_EQ(j["cost"].size(), 1u);  // a 1 x 1 value: an array of one number
  EXPECT_NEAR(j["cost"][0].get<double>(), e.squaredNorm(), 1e-12);

  // d cost / dq = 2 J^T e with J the tool's linear Jacobian (world-aligned); d / d target = -2 e.
  const Eigen::MatrixXd J = matrixOf(computeFunction("jacobian --frame tool --reference LOCAL_WORLD_ALIGNED")["value"]);
  Eigen::VectorXd grad(10);
  grad << 2.0 * J.topRows(3).transpose() * e, -2.0 * e;
  EXPECT_TRUE(matricesAgree(matrixOf(j["grad"]), grad, 1e-10));

  // The sparse Hessian comes out full and symmetric, and agrees with finite differences.
  const Eigen::MatrixXd H = matrixOf(j["hess"]);
  ASSERT_EQ(H.rows(), 7);
  ASSERT_EQ(H.cols(), 7);
  EXPECT_EQ((H - H.transpose()).cwiseAbs().maxCoeff(), 0.0);
  const json reference = computeUser("--backend reference");
  EXPECT_EQ(reference["backend"], "reference");
  EXPECT_EQ(reference["method"]["derivatives"], "central finite differences (approximate)");
  EXPECT_TRUE(matricesAgree(H, matrixOf(reference["hess"]), 1e-4));
  EXPECT_TRUE(matricesAgree(matrixOf(j["dv_next"]), matrixOf(reference["dv_next"]), 1e-5));
  EXPECT_TRUE(matricesAgree(matrixOf(j["v_next"]), matrixOf(reference["v_next"]), 1e-12));
}

TEST_F(UserSpecCli, ComputeTablesAndRandomStates) {
  testing::ProcessResult r = runCommand(runCli("compute " + arm7Path() + " --spec " + shellQuote(spec_.string()) +
                                            " --random-state 4 --format table --backend reference"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* text : {"euler_step of", "random state (seed 4)", "derivatives by central finite differences",
                           "dv_next (jacobian of v_next)", "grad (gradient of cost)", "q:joint1", "target[2]"})
    EXPECT_NE(r.out.find(text), std::string::npos) << text << " in\n" << r.out;
  const json a = parsedJson(runCli("compute " + arm7Path() + " --spec " + shellQuote(spec_.string()) + " --random-state 4"));
  const json b = parsedJson(runCli("compute " + arm7Path() + " --spec " + shellQuote(spec_.string()) + " --random-state 4"));
  EXPECT_EQ(a["v_next"], b["v_next"]);
}

TEST_F(UserSpecCli, ABadStateFileNamesTheInputAndListsTheExpectedOnes) {
  const std::string expected_inputs =
      "q (7 numbers, a configuration), v (7 numbers), u (7 numbers), target (3 numbers)";
  struct Case {
    std::string state, message;
  };
  const std::vector<Case> cases = {
      {R"({"q": )" + kQ + R"(, "v": )" + kV + R"(, "target": )" + kTarget + "}",
       "no \"u\"; the function's inputs are " + expected_inputs},
      {R"({"q": )" + kQ + R"(, "v": )" + kV + R"(, "u": )" + kU + R"(, "target": [1, 2]})",
       "\"target\" has 2 numbers, 3 expected; the function's inputs are " + expected_inputs},
      {R"({"q": )" + kQ + R"(, "v": )" + kV + R"(, "u": )" + kU + R"(, "target": [1, "x", 3]})",
       "\"target\"[1] is \"x\", not a number"},
  };
  for (const Case& c : cases) {
    const fs::path state = tmp_.file("bad.json", c.state);
    const testing::ProcessResult r = runCommand(
        runCli("compute " + arm7Path() + " --spec " + shellQuote(spec_.string()) + " --state " + shellQuote(state.string())));
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.err.find(state.string() + ": " + c.message), std::string::npos) << r.err;
  }
}

TEST_F(UserSpecCli, GenerateThenCheckPerOutputAndFailWithStatus2) {
  const fs::path out = tmp_.path() / "out";
  testing::ProcessResult r =
      runCommand(runCli("generate " + arm7Path() + " --spec " + shellQuote(spec_.string()) + " --out " + shellQuote(out.string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("euler_step (euler_step): q_next 7 x 1, v_next 7 x 1, dv_next 7 x 21"), std::string::npos)
      << r.out;
  const json d = json::parse(testing::readFile(out / "euler_step.json"));
  ASSERT_EQ(d["inputs"].size(), 4u);  // dt is fixed
  EXPECT_EQ(d["inputs"][3]["name"], "target");
  EXPECT_EQ(d["outputs"][4]["name"], "grad");

  const json check = parsedJson(runCli("check " + arm7Path() + " --spec " + shellQuote(spec_.string()) + " --samples 2 --json"));
  EXPECT_EQ(check["pass"], true) << check.dump(2);
  ASSERT_EQ(check["comparisons"].size(), 12u);  // 6 outputs, each vs its reference and the interpreter
  const std::vector<std::pair<std::string, std::string>> rows = {
      {"q_next", "double evaluation"}, {"dv_next", "finite differences"}, {"grad", "finite differences"},
      {"hess", "second finite differences"}};
  for (const auto& [output, against] : rows) {
    bool found = false;
    for (const json& c : check["comparisons"]) found = found || (c["output"] == output && c["against"] == against);
    EXPECT_TRUE(found) << output << " against " << against << "\n" << check.dump(2);
  }
  for (const json& c : check["comparisons"]) EXPECT_LE(c["worst_rel_error"].get<double>(), c["tolerance"].get<double>()) << c;

  // A compiler ($CC) that reads input block v where the code reads q: check fails, status 2.
  const fs::path cc =
      tmp_.script("sabotage-cc",
                  "for a in \"$@\"; do case \"$a\" in *.c) sed -i 's/in\\[0\\]/in[1]/g' \"$a\";; esac; done\n"
                  "exec cc \"$@\"\n");
  r = runCommand("CC=" + shellQuote(cc.string()) + " " +
                 runCli("check " + arm7Path() + " --spec " + shellQuote(spec_.string()) + " --samples 2"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.out.find("FAIL"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("dv_next"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace robodiff
