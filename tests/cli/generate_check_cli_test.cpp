// `robodiff generate`, `robodiff check` and `robodiff compute` with a spec or a backend,
// as a user runs them: real processes, files and JSON read back. Specs are the
// examples built at -O0 without -march=native, to keep the compiles short.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "support/cache_workspace.hpp"
#include "support/golden.hpp"
#include "support/process.hpp"
#include "support/json_matrix.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using nlohmann::json;
using testing::cliPath;
using testing::matricesAgree;
using testing::runCommand;
using testing::shellQuote;
using testing::TempDir;
using testing::matrixOf;

namespace fs = std::filesystem;

using testing::cli;

fs::path exampleSpec(const std::string& name) { return testing::sourceDir() / "examples/specs" / (name + ".json"); }

// The example spec `name`, built at -O0 for this machine's generic target.
fs::path fastSpec(const TempDir& tmp, const std::string& name) {
  json spec = json::parse(testing::readFile(exampleSpec(name)));
  spec["build"] = {{"optimization", "O0"}, {"march_native", false}};
  return tmp.file(name + ".json", spec.dump());
}

struct Robot {
  std::string label, args;  // args: --urdf FILE [--floating-base]
  int nq, nv;
};

Robot arm7() {
  return {"arm7", "--urdf " + shellQuote((testing::sourceDir() / "examples/robots/arm7.urdf").string()), 7, 7};
}
Robot quadruped() {
  return {
      "quadruped",
      "--urdf " + shellQuote((testing::sourceDir() / "examples/robots/quadruped.urdf").string()) + " --floating-base",
      19, 18};
}

// Runs a command expected to succeed and parses its JSON output.
json jsonOf(const std::string& command) {
  testing::ProcessResult r = runCommand(command);
  EXPECT_EQ(r.exit_code, 0) << command << "\n" << r.err;
  if (r.exit_code != 0) return json::object();
  return json::parse(r.out);
}

TEST(GenerateCli, WritesTheLibraryItsDescriptionAndSources) {
  TempDir tmp;
  const fs::path out = tmp.path() / "out";
  testing::ProcessResult r =
      runCommand(cli("generate " + arm7().args + " --spec " + shellQuote(fastSpec(tmp, "rnea_jacobian").string()) +
                     " --out " + shellQuote(out.string()) + " --name arm7_rnea"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* word : {"arm7_rnea", "operations", "compile", "peak memory", "arm7_rnea.so", "arm7_rnea.json"})
    EXPECT_NE(r.out.find(word), std::string::npos) << word << " in\n" << r.out;

  const fs::path library = out / "arm7_rnea.so";
  ASSERT_TRUE(fs::is_regular_file(library));
  EXPECT_EQ(testing::readFile(library).substr(0, 4),
            "\x7f"
            "ELF");
  const json d = json::parse(testing::readFile(out / "arm7_rnea.json"));
  EXPECT_EQ(d["name"], "arm7_rnea");
  EXPECT_EQ(d["model"]["nq"], 7);
  EXPECT_EQ(d["model"]["nv"], 7);
  ASSERT_EQ(d["inputs"].size(), 3u);
  for (int b = 0; b < 3; ++b) {
    EXPECT_EQ(d["inputs"][b]["name"], std::vector<std::string>({"q", "v", "a"})[b]);
    EXPECT_EQ(d["inputs"][b]["size"], 7);
  }
  ASSERT_EQ(d["outputs"].size(), 2u);
  EXPECT_EQ(d["outputs"][0]["name"], "value");
  EXPECT_EQ(d["outputs"][0]["rows"], 7);
  EXPECT_EQ(d["outputs"][0]["cols"], 1);
  EXPECT_EQ(d["outputs"][1]["name"], "jacobian");
  EXPECT_EQ(d["outputs"][1]["rows"], 7);
  EXPECT_EQ(d["outputs"][1]["cols"], 21);
  EXPECT_EQ(d["outputs"][1]["wrt"], std::vector<std::string>({"q", "v", "a"}));
  EXPECT_EQ(d["build"]["library"], "arm7_rnea.so");
  EXPECT_EQ(d["build"]["library_bytes"].get<std::uintmax_t>(), fs::file_size(library));
  int sources = 0;
  for (const auto& entry : fs::directory_iterator(out / "src")) sources += entry.path().extension() == ".c";
  EXPECT_GE(sources, 1);
}

struct SpecCase {
  Robot robot;
  std::string spec;
};

std::vector<SpecCase> specCases() {
  return {{arm7(), "rnea_jacobian"},
          {arm7(), "aba_jacobian"},
          {quadruped(), "rnea_jacobian"},
          {quadruped(), "aba_jacobian"}};
}

std::string caseName(const ::testing::TestParamInfo<int>& info) {
  const SpecCase c = specCases()[static_cast<std::size_t>(info.param)];
  return c.robot.label + "_" + c.spec;
}

class SpecCases : public ::testing::TestWithParam<int> {};

// The three backends of compute agree: the generated code and the interpreter with the
// double reference (value from core/dynamics, Jacobian from the graph evaluated alone).
TEST_P(SpecCases, ComputeBackendsAgree) {
  const SpecCase c = specCases()[static_cast<std::size_t>(GetParam())];
  TempDir tmp;
  const std::string base = "compute " + c.robot.args + " --spec " + shellQuote(fastSpec(tmp, c.spec).string()) +
                           " --cache " + shellQuote((tmp / "cache").string()) +
                           " --derivatives --random-state 7 --backend ";
  const json reference = jsonOf(cli(base + "reference"));
  ASSERT_TRUE(reference.contains("jacobian")) << reference;
  const Eigen::MatrixXd value = matrixOf(reference["value"]), jacobian = matrixOf(reference["jacobian"]);
  EXPECT_EQ(reference["nq"], c.robot.nq);
  EXPECT_EQ(value.rows(), c.robot.nv);
  EXPECT_EQ(value.cols(), 1);
  EXPECT_EQ(jacobian.rows(), c.robot.nv);
  EXPECT_EQ(jacobian.cols(), 3 * c.robot.nv);
  // ABA solves with the mass matrix: the generated sums and the double reference's round
  // apart by up to 1.5e-12 relative on entries under 1 (the quadruped, twelve random
  // states, in either order of the sums' terms).
  const double value_tolerance = c.spec == "aba_jacobian" ? 5e-12 : 1e-12;
  for (const std::string backend : {"generated", "interpreted"}) {
    SCOPED_TRACE(backend);
    const json j = jsonOf(cli(base + backend));
    EXPECT_EQ(j["backend"], backend);
    EXPECT_TRUE(matricesAgree(matrixOf(j["value"]), value, value_tolerance));
    EXPECT_TRUE(matricesAgree(matrixOf(j["jacobian"]), jacobian, 1e-9));
  }
}

// check passes on the example specs; --json gives one row per output and comparison.
TEST_P(SpecCases, CheckPasses) {
  const SpecCase c = specCases()[static_cast<std::size_t>(GetParam())];
  TempDir tmp;
  const json j = jsonOf(
      cli("check " + c.robot.args + " --spec " + shellQuote(fastSpec(tmp, c.spec).string()) + " --samples 3 --json"));
  EXPECT_EQ(j["pass"], true) << j.dump(2);
  EXPECT_EQ(j["samples"], 3);
  ASSERT_EQ(j["comparisons"].size(), 4u) << j.dump(2);  // value, jacobian: each vs reference and interpreter
  for (const json& row : j["comparisons"]) {
    EXPECT_EQ(row["pass"], true) << row;
    EXPECT_LE(row["worst_rel_error"].get<double>(), row["tolerance"].get<double>()) << row;
  }
  EXPECT_EQ(j["comparisons"][2]["output"], "jacobian");
  EXPECT_EQ(j["comparisons"][2]["against"], "finite differences");
  EXPECT_EQ(j["comparisons"][3]["against"], "interpreted");
}

INSTANTIATE_TEST_SUITE_P(ExampleSpecs, SpecCases, ::testing::Range(0, 4), caseName);

// --function with a backend or --derivatives builds the same function as a spec would,
// at the same random state as the original output.
TEST(ComputeCli, FunctionWithABackendMatchesTheDirectOutput) {
  const std::string base = "compute " + arm7().args + " --random-state 3 ";
  const json direct = jsonOf(cli(base + "--function rnea"));
  const json interpreted = jsonOf(cli(base + "--function rnea --backend interpreted"));
  EXPECT_TRUE(matricesAgree(matrixOf(interpreted["value"]), matrixOf(direct["value"]), 1e-12));
  EXPECT_FALSE(interpreted.contains("jacobian"));

  const json frame = jsonOf(cli(base + "--function jacobian --frame tool --reference WORLD"));
  const json with_derivatives =
      jsonOf(cli(base + "--function jacobian --frame tool --reference WORLD --derivatives --backend interpreted"));
  EXPECT_EQ(with_derivatives["frame"], "tool");
  EXPECT_EQ(with_derivatives["reference"], "WORLD");
  EXPECT_TRUE(matricesAgree(matrixOf(with_derivatives["value"]), matrixOf(frame["value"]), 1e-12));
  EXPECT_EQ(matrixOf(with_derivatives["jacobian"]).rows(), 6 * 7);  // the 6 x 7 value, flattened
  EXPECT_EQ(matrixOf(with_derivatives["jacobian"]).cols(), 7);
}

TEST(ComputeCli, SpecHessianIsSymmetricAndReadsTheWeights) {
  TempDir tmp;
  const fs::path spec = exampleSpec("rnea_hessian");
  const std::string q = "[0.1, -0.4, 0.7, -1.0, 0.3, 0.5, -0.2]", v = "[0.5, 0.1, -0.3, 0.2, 0.9, -0.6, 0.4]";
  const fs::path state = tmp.file("state.json", R"({"q": )" + q + R"(, "v": )" + v + R"(, "a": )" + v +
                                                    R"(, "weights": [1, -2, 0.5, 3, 0.25, -1, 2]})");
  const std::string base = "compute " + arm7().args + " --spec " + shellQuote(spec.string()) + " --state " +
                           shellQuote(state.string()) + " --derivatives --backend ";
  const json interpreted = jsonOf(cli(base + "interpreted"));
  const json reference = jsonOf(cli(base + "reference"));
  const Eigen::MatrixXd H = matrixOf(interpreted["hessian"]);
  ASSERT_EQ(H.rows(), 7);
  ASSERT_EQ(H.cols(), 7);
  EXPECT_EQ((H - H.transpose()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(H.cwiseAbs().maxCoeff(), 0.1);
  EXPECT_TRUE(matricesAgree(H, matrixOf(reference["hessian"]), 1e-9));
  EXPECT_EQ(matrixOf(interpreted["jacobian"]).cols(), 7);  // the spec's Jacobian in q

  // Without --derivatives only the value; without weights in the state, a clear error.
  const json value_only = jsonOf(cli("compute " + arm7().args + " --spec " + shellQuote(spec.string()) + " --state " +
                                     shellQuote(state.string())));
  EXPECT_TRUE(value_only.contains("value"));
  EXPECT_FALSE(value_only.contains("hessian"));
  const fs::path no_weights = tmp.file("no_weights.json", R"({"q": )" + q + R"(, "v": )" + v + R"(, "a": )" + v + "}");
  testing::ProcessResult r =
      runCommand(cli("compute " + arm7().args + " --spec " + shellQuote(spec.string()) +
                     " --derivatives --backend interpreted --state " + shellQuote(no_weights.string())));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no \"weights\""), std::string::npos) << r.err;
}

TEST(CheckCli, PrintsATableAndFailsWithStatus2) {
  TempDir tmp;
  const fs::path spec = fastSpec(tmp, "rnea_jacobian");
  testing::ProcessResult r = runCommand(
      cli("check " + arm7().args + " --spec " + shellQuote(spec.string()) + " --samples 2 --backend interpreted"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("finite differences"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("PASS"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("all 2 comparisons pass"), std::string::npos) << r.out;

  // A compiler ($CC) that swaps the q input for v in the generated code before compiling.
  const fs::path cc =
      tmp.script("sabotage-cc",
                 "for a in \"$@\"; do case \"$a\" in *.c) sed -i 's/in\\[0\\]/in[1]/g' \"$a\";; esac; done\n"
                 "exec cc \"$@\"\n");
  r = runCommand("CC=" + shellQuote(cc.string()) + " " +
                 cli("check " + arm7().args + " --spec " + shellQuote(spec.string()) + " --samples 2"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.out.find("FAIL"), std::string::npos) << r.out;
}

struct BadGenerateCase {
  std::string label, spec, extra, expected;
};

TEST(GenerateCli, ErrorsNameTheProblem) {
  TempDir tmp;
  const fs::path failing_cc = tmp.script("fake-cc", "echo 'fake compiler failure: boom' >&2\nexit 1\n");
  const std::vector<BadGenerateCase> cases = {
      {"unknown input in wrt", R"({"function": "rnea", "outputs": [{"kind": "jacobian", "wrt": ["q", "x"]}]})", "",
       "outputs[0].wrt[1]"},
      {"unknown build field",
       R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"optimisation": "O1"}})", "",
       "build.optimisation"},
      {"unknown frame", R"({"function": "fk", "frame": "nowhere", "outputs": [{"kind": "value"}]})", "", "nowhere"},
      {"compiler failure", R"({"function": "gravity", "outputs": [{"kind": "value"}]})",
       "--compiler " + shellQuote(failing_cc.string()), "fake compiler failure: boom"},
  };
  for (const BadGenerateCase& c : cases) {
    SCOPED_TRACE(c.label);
    const fs::path out = tmp.path() / "out";
    testing::ProcessResult r =
        runCommand(cli("generate " + arm7().args + " --spec " + shellQuote(tmp.file("spec.json", c.spec).string()) +
                       " --out " + shellQuote(out.string()) + " " + c.extra));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("robodiff: error: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "gravity.so"));
  }
}

}  // namespace
}  // namespace robodiff
