// Reading trajectories for a function: columns by joint name or index mapped onto its
// input blocks, a floating base's columns, JSON in both shapes, and every kind of bad
// file reported by file, line (or JSON path), column and text.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "robodiff/batch/trajectory_error.hpp"
#include "robodiff/batch/trajectory_table.hpp"
#include "trajectory/trajectory_fixtures.hpp"

namespace robodiff::testing {
namespace {

using batch::BlockLayout;
using batch::TrajectoryError;
using batch::TrajectoryTable;

// rnea's blocks for a robot with nq, nv, as BatchFunction lays them out.
std::vector<BlockLayout> blocks(std::uint32_t nq, std::uint32_t nv, const std::vector<std::string>& names = {"q", "v", "a"}) {
  std::vector<BlockLayout> out;
  std::uint32_t offset = 0;
  for (const std::string& name : names) {
    BlockLayout b;
    b.name = name;
    b.size = b.rows = name == "q" ? nq : nv;
    b.cols = 1;
    b.offset = offset;
    offset += b.size;
    out.push_back(b);
  }
  return out;
}

class TrajectoryTableTest : public ::testing::Test {
 protected:
  Robot arm_{"arm7"};
  std::vector<BlockLayout> rnea_ = blocks(7, 7);
  std::vector<std::string> joints_ = arm_.model.jointNames();

  // A header by joint name for q, v, a (plus `extra`), and rows of 22 numbers.
  std::string header(const std::string& extra = "") const {
    std::string h = "t";
    for (const char* block : {"q", "v", "a"})
      for (const std::string& j : joints_) h += std::string(",") + block + "_" + j;
    return h + extra + "\n";
  }
  static std::string row(double base, const std::string& extra = "") {
    std::string r = shortest(base);
    for (int i = 0; i < 21; ++i) r.append(",").append(shortest(base + 0.01 * i));
    return r + extra + "\n";
  }
};

TEST_F(TrajectoryTableTest, ColumnsByJointNameFillTheBlocksInLayoutOrder) {
  // Columns in any order: a, then q reversed, then v, then t last.
  std::string h;
  for (const std::string& j : joints_) h += "a_" + j + ",";
  for (auto j = joints_.rbegin(); j != joints_.rend(); ++j) h += "q_" + *j + ",";
  for (const std::string& j : joints_) h += "v_" + j + ",";
  h += "tau_" + joints_[0] + ",t\n";
  std::string r;
  for (int i = 0; i < 7; ++i) r += shortest(300 + i) + ",";
  for (int i = 6; i >= 0; --i) r += shortest(100 + i) + ",";
  for (int i = 0; i < 7; ++i) r += shortest(200 + i) + ",";
  r += "99,0.25\n";
  const TrajectoryTable table = batch::parseTrajectoryCsv(h + r + r, "traj.csv", arm_.model, rnea_);
  ASSERT_EQ(table.knots, 2u);
  EXPECT_EQ(table.input_count, 21u);
  EXPECT_EQ(table.times, (std::vector<double>{0.25, 0.25}));
  EXPECT_EQ(table.lines, (std::vector<std::uint64_t>{2, 3}));
  for (int b = 0; b < 3; ++b)
    for (int i = 0; i < 7; ++i) EXPECT_EQ(table.inputs[21 + 7 * b + i], 100 * (b + 1) + i) << b << " " << i;
  EXPECT_EQ(table.ignored_columns, (std::vector<std::string>{"tau_" + joints_[0]}));
  EXPECT_EQ(table.block_columns[0][0], "q_" + joints_[0]);
}

TEST_F(TrajectoryTableTest, ColumnsByIndexAndNoTime) {
  std::string h = "q_0";
  for (int i = 1; i < 7; ++i) h += ",q_" + std::to_string(i);
  for (const char* block : {"v", "a"})
    for (int i = 0; i < 7; ++i) h += std::string(",") + block + "_" + std::to_string(i);
  std::string r = "0";
  for (int i = 1; i < 21; ++i) r.append(",").append(std::to_string(i));
  const TrajectoryTable table = batch::parseTrajectoryCsv(h + "\n" + r + "\n", "traj.csv", arm_.model, rnea_);
  ASSERT_EQ(table.knots, 1u);
  EXPECT_TRUE(table.times.empty());
  for (int i = 0; i < 21; ++i) EXPECT_EQ(table.inputs[i], i);
}

TEST_F(TrajectoryTableTest, AMissingColumnNamesTheBlockAndTheColumns) {
  std::string h = header();
  const std::string gone = ",v_" + joints_[2];
  h.erase(h.find(gone), gone.size());
  std::string r = row(1);
  r.erase(r.rfind(','));  // one field less, as the header
  EXPECT_EQ(errorOf([&] { batch::parseTrajectoryCsv(h + r, "traj.csv", arm_.model, rnea_); }),
            "traj.csv:1: input block 'v' (7 entries) needs the columns v_" + joints_[0] + " .. v_" + joints_[6] +
                " (by joint) or v_0 .. v_6 (by index); missing: v_" + joints_[2]);
}

TEST_F(TrajectoryTableTest, BadRowsReportTheirLineAndColumn) {
  const std::string good = header() + row(0) + "# comment\n" + row(1);
  // Line 5 (after the header, two rows and a comment): a field too few.
  std::string short_row = row(2);
  short_row.erase(short_row.rfind(','));
  EXPECT_EQ(errorOf([&] { batch::parseTrajectoryCsv(good + short_row, "traj.csv", arm_.model, rnea_); }),
            "traj.csv:5: 21 fields, the header (line 1) has 22");
  // A word, a nan, an inf in q_<joint 3>.
  for (const std::string bad : {"abc", "nan", "inf"}) {
    std::string r = row(2);
    std::size_t at = 0;
    for (int i = 0; i < 3; ++i) at = r.find(',', at) + 1;  // t, q0, q1, then q2's field
    r.replace(at, r.find(',', at) - at, bad);
    const std::string what = bad == "abc" ? "is not a number" : "is not finite";
    EXPECT_EQ(errorOf([&] { batch::parseTrajectoryCsv(good + "\n" + r, "traj.csv", arm_.model, rnea_); }),
              "traj.csv:6: column q_" + joints_[2] + ": '" + bad + "' " + what);
  }
}

// Large files are parsed on several threads; the earliest bad line is the one reported.
TEST_F(TrajectoryTableTest, ALargeFileReportsItsFirstBadLine) {
  std::string csv = header();
  for (int k = 0; k < 40000; ++k) csv += k == 30000 ? row(k, "").replace(0, 1, "x") : k == 20001 ? "1,2\n" : row(k);
  EXPECT_EQ(errorOf([&] { batch::parseTrajectoryCsv(csv, "big.csv", arm_.model, rnea_); }),
            "big.csv:20003: 2 fields, the header (line 1) has 22");
  const std::size_t at = csv.find("1,2\n");
  csv.replace(at, 4, row(20001));
  EXPECT_EQ(errorOf([&] { batch::parseTrajectoryCsv(csv, "big.csv", arm_.model, rnea_); }).substr(0, 31),
            "big.csv:30002: column t: 'x0000");
  csv = header();
  for (int k = 0; k < 40000; ++k) csv += row(k);
  const TrajectoryTable table = batch::parseTrajectoryCsv(csv, "big.csv", arm_.model, rnea_);
  ASSERT_EQ(table.knots, 40000u);
  for (std::uint64_t k = 0; k < table.knots; k += 997) {
    EXPECT_EQ(table.lines[k], k + 2);
    EXPECT_EQ(table.times[k], static_cast<double>(k));
    EXPECT_EQ(table.inputs[k * 21 + 20], static_cast<double>(k) + 0.01 * 20);
  }
}

TEST_F(TrajectoryTableTest, UnusedColumnsMayHoldAnything) {
  const TrajectoryTable table =
      batch::parseTrajectoryCsv(header(",comment,tau_x") + row(0, ",hello,n/a") + row(1, ",,"), "t.csv", arm_.model, rnea_);
  EXPECT_EQ(table.knots, 2u);
  EXPECT_EQ(table.ignored_columns, (std::vector<std::string>{"comment", "tau_x"}));
}

TEST_F(TrajectoryTableTest, HessianWeightsByJointOrIndex) {
  const std::vector<BlockLayout> with_weights = blocks(7, 7, {"q", "v", "a", "weights"});
  std::string h = header();
  h.pop_back();
  for (int i = 0; i < 7; ++i) h += ",weights_" + std::to_string(i);
  std::string r = row(0);
  r.pop_back();
  for (int i = 0; i < 7; ++i) r += ",0.5";
  const TrajectoryTable table = batch::parseTrajectoryCsv(h + "\n" + r + "\n", "w.csv", arm_.model, with_weights);
  EXPECT_EQ(table.inputs[21], 0.5);
  EXPECT_EQ(table.block_columns[3][0], "weights_0");
  EXPECT_EQ(batch::jointColumns(arm_.model, with_weights[3])[0], "weights_" + joints_[0]);
}

TEST(TrajectoryTableFloatingBase, NamesTheBaseCoordinatesAndChecksTheQuaternion) {
  Robot humanoid("humanoid", true);
  const Model& model = humanoid.model;
  const std::vector<BlockLayout> layout = blocks(model.nq, model.nv);
  const std::vector<std::string> q = batch::jointColumns(model, layout[0]);
  const std::vector<std::string> v = batch::jointColumns(model, layout[1]);
  ASSERT_EQ(q.size(), static_cast<std::size_t>(model.nq));
  ASSERT_EQ(v.size(), static_cast<std::size_t>(model.nv));
  EXPECT_EQ(std::vector<std::string>(q.begin(), q.begin() + 7),
            (std::vector<std::string>{"q_root_joint_x", "q_root_joint_y", "q_root_joint_z", "q_root_joint_qx",
                                      "q_root_joint_qy", "q_root_joint_qz", "q_root_joint_qw"}));
  EXPECT_EQ(std::vector<std::string>(v.begin(), v.begin() + 6),
            (std::vector<std::string>{"v_root_joint_vx", "v_root_joint_vy", "v_root_joint_vz", "v_root_joint_wx",
                                      "v_root_joint_wy", "v_root_joint_wz"}));
  EXPECT_EQ(q[7], "q_" + model.joints[1].name);

  std::string h;  // q, v, a by joint name
  for (const std::string& name : q) h += (h.empty() ? "" : ",") + name;
  for (const std::string& name : v) h += "," + name;
  for (const std::string& name : v) h += ",a" + name.substr(1);
  auto knot = [&](double qw) {
    std::string line = "0,0,1,0,0,0," + shortest(qw);
    for (int i = 7; i < model.nq + 2 * model.nv; ++i) line += ",0.1";
    return line + "\n";
  };
  const TrajectoryTable table = batch::parseTrajectoryCsv(h + "\n" + knot(1.0), "base.csv", model, layout);
  EXPECT_EQ(table.inputs[6], 1.0);
  EXPECT_EQ(errorOf([&] { batch::parseTrajectoryCsv(h + "\n" + knot(1.0) + knot(0.5), "base.csv", model, layout); }),
            "base.csv:3: columns q_root_joint_qx .. q_root_joint_qw: the quaternion has norm 0.5, not 1");
}

// A user function's configuration inputs, whatever their names, are read as q is: by
// joint coordinate (the base's x .. qw), the quaternion checked.
TEST(TrajectoryTableUserFunction, ConfigurationInputsByTheirOwnNames) {
  Robot humanoid("humanoid", true);
  const Model& model = humanoid.model;
  const FunctionSpec spec = parseFunctionSpec(R"({"inputs": {"q0": "configuration", "q1": "configuration", "w": "nv"},
      "outputs": [{"name": "d", "kind": "value", "of": "difference(q0, q1) + w"}]})");
  const std::vector<std::string> configurations = batch::configurationInputs(spec);
  EXPECT_EQ(configurations, (std::vector<std::string>{"q0", "q1"}));
  EXPECT_EQ(batch::configurationInputs(parseFunctionSpec(kRneaJacobian)), std::vector<std::string>{"q"});

  std::vector<BlockLayout> layout = blocks(model.nq, model.nv, {"q", "q", "w"});
  layout[0].name = "q0", layout[1].name = "q1";
  std::string h;
  for (const BlockLayout& block : layout)
    for (const std::string& name : batch::jointColumns(model, block, configurations)) h += (h.empty() ? "" : ",") + name;
  EXPECT_NE(h.find("q1_root_joint_qw,q1_" + model.joints[1].name), std::string::npos) << h;
  EXPECT_NE(h.find("w_root_joint_wz"), std::string::npos) << h;
  auto knot = [&](double qw) {
    std::string line = "0,0,1,0,0,0,1";
    for (int i = 7; i < model.nq; ++i) line += ",0.1";
    line += ",0,0,1,0,0,0," + shortest(qw);
    for (int i = 7; i < model.nq + model.nv; ++i) line += ",0.2";
    return line + "\n";
  };
  const TrajectoryTable table = batch::parseTrajectoryCsv(h + "\n" + knot(1.0), "two.csv", model, layout, configurations);
  EXPECT_EQ(table.inputs[static_cast<std::size_t>(model.nq) + 6], 1.0);
  EXPECT_EQ(table.inputs.back(), 0.2);
  EXPECT_EQ(errorOf([&] { batch::parseTrajectoryCsv(h + "\n" + knot(0.5), "two.csv", model, layout, configurations); }),
            "two.csv:2: columns q1_root_joint_qx .. q1_root_joint_qw: the quaternion has norm 0.5, not 1");
}

TEST_F(TrajectoryTableTest, JsonBlockMajorAndKnotMajorAgree) {
  nlohmann::json block_major = {{"t", {0.0, 0.5}}, {"q", nlohmann::json::array()}, {"v", nlohmann::json::array()},
                                {"a", nlohmann::json::array()}, {"label", "walk"}};
  nlohmann::json knot_major = nlohmann::json::array();
  for (int k = 0; k < 2; ++k) {
    nlohmann::json knot = {{"t", 0.5 * k}, {"extra", 1}};
    for (const char* b : {"q", "v", "a"}) {
      std::vector<double> values;
      for (int i = 0; i < 7; ++i) values.push_back(k * 100 + (b[0] - 'a') + 0.1 * i);
      block_major[b].push_back(values);
      knot[b] = values;
    }
    knot_major.push_back(knot);
  }
  const TrajectoryTable a = batch::parseTrajectoryJson(block_major.dump(), "b.json", arm_.model, rnea_);
  const TrajectoryTable b = batch::parseTrajectoryJson(knot_major.dump(2), "k.json", arm_.model, rnea_);
  EXPECT_EQ(a.knots, 2u);
  EXPECT_EQ(a.inputs, b.inputs);
  EXPECT_EQ(a.times, b.times);
  EXPECT_EQ(a.ignored_columns, (std::vector<std::string>{"label"}));
  EXPECT_EQ(b.ignored_columns, (std::vector<std::string>{"extra"}));
  EXPECT_EQ(a.inputs[21 + 7 + 3], 100 + ('v' - 'a') + 0.3);
}

TEST_F(TrajectoryTableTest, JsonErrorsNameThePath) {
  auto parse = [&](const std::string& text) { batch::parseTrajectoryJson(text, "traj.json", arm_.model, rnea_); };
  const std::string seven = "[0,0,0,0,0,0,0]";
  EXPECT_EQ(errorOf([&] { parse(R"({"q": [)" + seven + "], \"v\": [" + seven + "]}"); }),
            "traj.json: no \"a\": input block 'a' needs an array of 7 numbers per knot");
  EXPECT_EQ(errorOf([&] { parse(R"({"q": [)" + seven + "], \"v\": [" + seven + "], \"a\": [[0,0,\"x\",0,0,0,0]]}"); }),
            "traj.json: a[0][2]: \"x\" is not a number");
  EXPECT_EQ(errorOf([&] { parse(R"({"q": [)" + seven + "," + seven + "], \"v\": [" + seven + "], \"a\": [" + seven + "]}"); }),
            "traj.json: v: 1 knots, q has 2");
  EXPECT_EQ(errorOf([&] { parse("[{\"q\": " + seven + ", \"v\": [0,0], \"a\": " + seven + "}]"); }),
            "traj.json: [0].v: 2 entries, input block 'v' has 7");
  EXPECT_EQ(errorOf([&] { parse("{\n\"q\": [\n[0,0,,]]}"); }).rfind("traj.json:3: not valid JSON", 0), 0u);
}

}  // namespace
}  // namespace robodiff::testing
