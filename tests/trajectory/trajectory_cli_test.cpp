// `robodiff trajectory` as a user runs it: a real process reading a CSV or JSON
// trajectory, writing CSV or binary outputs equal to the library's, and bad files
// reported by file and line with exit status 1 and no output.
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/batch/csv_table.hpp"
#include "robodiff/batch/trajectory_evaluation.hpp"
#include "support/cache_workspace.hpp"
#include "support/process.hpp"
#include "trajectory/trajectory_fixtures.hpp"

namespace robodiff::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class TrajectoryCliTest : public ::testing::Test {
 protected:
  std::string trajectory(const fs::path& data, const fs::path& out, const std::string& extra = "") const {
    return cli("trajectory --urdf " + shellQuote(arm_.urdf_path.string()) + " --spec " + shellQuote(spec_path_.string()) +
               " --data " + shellQuote(data.string()) + " --out " + shellQuote(out.string()) + " " + extra);
  }
  // The outputs of the interpreter on `data`, read by the library.
  batch::TrajectoryOutput expected(const fs::path& data) const {
    const batch::BatchFunction f = arm_.open(spec_, batch::Backend::Interpreted, tmp_ / "unused-cache");
    return batch::evaluateTrajectory(f, batch::readTrajectoryFile(data, arm_.model, f.inputs())).output;
  }
  fs::path csvData(std::uint64_t knots) const {
    const batch::BatchFunction f = arm_.open(spec_, batch::Backend::Interpreted, tmp_ / "unused-cache");
    return tmp_.file("traj.csv", trajectoryCsv(arm_.model, f, randomKnots(arm_.model, spec_, knots)));
  }

  TempDir tmp_;
  Robot arm_{"arm7"};
  FunctionSpec spec_ = parseFunctionSpec(kRneaJacobian);
  fs::path spec_path_ = tmp_.file("rnea_jacobian.json", kRneaJacobianQuickBuild);
};

TEST_F(TrajectoryCliTest, CompiledCsvOutputEqualsTheLibrary) {
  const fs::path data = csvData(300);
  const fs::path out = tmp_ / "out.csv";
  const ProcessResult r =
      runCommand(trajectory(data, out, "--cache " + shellQuote((tmp_ / "cache").string()) + " --threads 2 --json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json summary = json::parse(r.out);
  EXPECT_EQ(summary["knots"], 300);
  EXPECT_EQ(summary["backend"], "compiled");
  EXPECT_EQ(summary["format"], "csv");
  EXPECT_EQ(summary["function"], "rnea");
  EXPECT_EQ(summary["ignored_columns"], json::array({"note"}));
  EXPECT_GT(summary["knots_per_second"].get<double>(), 0.0);
  EXPECT_EQ(summary["bytes"], fs::file_size(out));

  const batch::TrajectoryOutput want = expected(data);
  const batch::CsvTable csv = batch::CsvTable::readFile(out);
  ASSERT_EQ(csv.rows(), 300u);
  EXPECT_EQ(csv.header()[0], "t");
  // Named by joint: the value's rows, the Jacobian's rows and its columns by input.
  const std::string first = arm_.model.joints.front().name, second = arm_.model.joints[1].name;
  const std::size_t nv = static_cast<std::size_t>(arm_.model.nv);
  EXPECT_EQ(csv.header()[1], "value_" + first);
  EXPECT_EQ(csv.header()[2], "value_" + second);
  EXPECT_EQ(csv.header()[1 + nv], "jacobian_" + first + "_q_" + first);
  EXPECT_EQ(csv.header()[2 + nv], "jacobian_" + first + "_q_" + second);
  EXPECT_EQ(csv.header()[1 + 2 * nv], "jacobian_" + first + "_v_" + first);
  EXPECT_EQ(csv.header()[1 + nv + 3 * nv], "jacobian_" + second + "_q_" + first);
  for (std::size_t k = 0; k < csv.rows(); ++k) {
    ASSERT_EQ(csv.number(k, 0), want.times[k]);
    for (std::size_t i = 0; i < want.output_count; ++i)
      ASSERT_NEAR(csv.number(k, i + 1), want.knot(k)[i], 1e-9 * (1 + std::abs(want.knot(k)[i]))) << k << " " << i;
  }
}

TEST_F(TrajectoryCliTest, JsonInBinaryOutAndASummaryForPeople) {
  const auto states = randomKnots(arm_.model, spec_, 25);
  json data = {{"t", json::array()}, {"q", json::array()}, {"v", json::array()}, {"a", json::array()}};
  for (std::size_t k = 0; k < states.size(); ++k) {
    data["t"].push_back(0.1 * static_cast<double>(k));
    for (int b = 0; b < 3; ++b)
      data[std::string(1, "qva"[b])].push_back(std::vector<double>(states[k][b].data(), states[k][b].data() + 7));
  }
  const fs::path path = tmp_.file("traj.json", data.dump());
  const fs::path out = tmp_ / "out.rdb";
  const ProcessResult r = runCommand(trajectory(path, out, "--backend interpreted"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("trajectory: 25 knots of rnea (value 7, jacobian 7 x 21)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("knots/s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(out.string()), std::string::npos) << r.out;
  const batch::TrajectoryOutput got = batch::readTrajectoryBinary(out);
  const batch::TrajectoryOutput want = expected(path);
  EXPECT_EQ(got.knots, 25u);
  EXPECT_EQ(got.times, want.times);
  EXPECT_EQ(got.values, want.values);  // the same interpreter, the same doubles
}

TEST_F(TrajectoryCliTest, ABadRowIsReportedByLineAndNothingIsWritten) {
  const fs::path data = csvData(12);
  std::string text = readFile(data);
  // Line 9 (knot 7): its first q field becomes a word.
  std::size_t at = 0;
  for (int line = 1; line < 9; ++line) at = text.find('\n', at) + 1;
  const std::size_t field = text.find(',', at) + 1;
  text.replace(field, text.find(',', field) - field, "1.2.3");
  tmp_.file("traj.csv", text);
  const fs::path out = tmp_ / "out.csv";
  const ProcessResult r = runCommand(trajectory(data, out, "--backend interpreted"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(data.string() + ":9: column q_" + arm_.model.joints[0].name + ": '1.2.3' is not a number"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(TrajectoryCliTest, AMissingColumnAndABadExtensionAreErrors) {
  const fs::path data = tmp_.file("few.csv", "t,q_0,q_1\n0,1,2\n");
  ProcessResult r = runCommand(trajectory(data, tmp_ / "out.csv", "--backend interpreted"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("few.csv:1: input block 'q' (7 entries) needs the columns"), std::string::npos) << r.err;
  r = runCommand(trajectory(data, tmp_ / "out.xlsx", "--backend interpreted"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("out.xlsx: the extension says no output format"), std::string::npos) << r.err;
}

// A user spec: input columns by input name (q_<joint>, u_<joint>, target_<i>), output
// columns by output name (q_next_<r>, dv_next_<r>_u_<joint>, cost_0, grad_q_<joint>).
TEST_F(TrajectoryCliTest, UserSpecColumnsByInputAndOutputName) {
  const char* text = R"js({"name": "step",
    "inputs": {"q": "configuration", "v": "nv", "u": "nv", "target": 3, "dt": {"fixed": [0.01]}},
    "define": {"v_next": "v + dt * aba(q, v, u)", "cost": "sumsq(frame_position(q, 'tool') - target)"},
    "outputs": [
      {"name": "q_next", "kind": "value", "of": "integrate(q, dt * v_next)"},
      {"name": "dv_next", "kind": "jacobian", "of": "v_next", "wrt": ["u"], "layout": "sparse"},
      {"name": "cost", "kind": "value", "of": "cost"},
      {"name": "grad", "kind": "gradient", "of": "cost", "wrt": ["q", "target"]}]})js";
  const FunctionSpec user = parseFunctionSpec(text);
  const fs::path spec = tmp_.file("step.json", text);
  const batch::BatchFunction f = arm_.open(user, batch::Backend::Interpreted, tmp_ / "unused-cache");
  const fs::path data = tmp_.file("step.csv", trajectoryCsv(arm_.model, f, randomKnots(arm_.model, user, 20)));
  const std::string header = readFile(data).substr(0, readFile(data).find('\n'));
  for (const std::string& column : {"q_" + arm_.model.joints[0].name, "u_" + arm_.model.joints[6].name, std::string("target_2")})
    EXPECT_NE(header.find("," + column), std::string::npos) << header;

  const fs::path out = tmp_ / "step_out.csv";
  const ProcessResult r =
      runCommand(cli("trajectory --urdf " + shellQuote(arm_.urdf_path.string()) + " --spec " + shellQuote(spec.string()) +
                     " --data " + shellQuote(data.string()) + " --out " + shellQuote(out.string()) +
                     " --backend interpreted --json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json summary = json::parse(r.out);
  EXPECT_EQ(summary["function"], "step");
  EXPECT_EQ(summary["knots"], 20);
  EXPECT_EQ(summary["ignored_columns"], json::array({"note"}));

  const batch::CsvTable csv = batch::CsvTable::readFile(out);
  const std::vector<std::string> want_header = {"t", "q_next_0"};
  EXPECT_EQ(std::vector<std::string>(csv.header().begin(), csv.header().begin() + 2), want_header);
  // A Jacobian's columns and a gradient's entries by the input they differentiate against.
  const std::string last = arm_.model.joints[6].name;
  for (const std::string& column : {std::string("q_next_6"), "dv_next_6_u_" + last, std::string("cost_0"),
                                    "grad_q_" + arm_.model.joints[0].name, std::string("grad_target_2")})
    EXPECT_TRUE(csv.column(column)) << column;
  const batch::TrajectoryOutput want =
      batch::evaluateTrajectory(f, batch::readTrajectoryFile(data, arm_.model, f.inputs(), batch::configurationInputs(user)))
          .output;
  ASSERT_EQ(csv.rows(), 20u);
  for (std::size_t k = 0; k < csv.rows(); ++k)
    for (std::size_t i = 0; i < want.output_count; ++i) ASSERT_EQ(csv.number(k, i + 1), want.knot(k)[i]) << k << " " << i;
}

}  // namespace
}  // namespace robodiff::testing
