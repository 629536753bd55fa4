// Measured samples from CSV: the columns named after the model's joints in any order,
// comments, blank lines, CRLF and extra columns accepted; every problem reported with the
// file, the 1-based line, the column and the text; writing and reading back gives the
// same doubles.
#include <gtest/gtest.h>

#include "identification_fixture.hpp"
#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/measured_samples.hpp"
#include "support/temp_dir.hpp"

namespace robodiff::testing {
namespace {

using batch::IdentificationError;
using batch::parseMeasuredSamples;

// A two-joint robot, so that CSV text stays short.
const char* kTwoJoints = R"(<robot name="two">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="10" velocity="2"/></joint>
  <link name="l1"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="2"/></joint>
  <link name="l2"><inertial><mass value="0.5"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
</robot>)";

const Model& twoJoints() {
  static const Model model = loadUrdfString(kTwoJoints);
  return model;
}

const char* kHeader = "t,q_j1,q_j2,v_j1,v_j2,a_j1,a_j2,tau_j1,tau_j2\n";

std::string errorOf(const std::string& text) {
  try {
    parseMeasuredSamples(text, twoJoints(), "samples.csv");
  } catch (const IdentificationError& e) {
    return e.what();
  }
  return "no error";
}

TEST(MeasuredSamples, ReadsColumnsByNameInAnyOrder) {
  const std::string text =
      "# recorded on the bench\n"
      "tau_j2, q_j1 ,\"q_j2\",v_j1,v_j2,a_j1,a_j2,tau_j1,current_j1\r\n"
      "\n"
      "8,1,2,3,4,5,6,7,whatever\r\n"
      "-8e-1, +1.5 ,2,3,4,5,6,7,\n";
  const batch::MeasuredSamples s = parseMeasuredSamples(text, twoJoints(), "samples.csv");
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s.q(0, 0), 1);
  EXPECT_EQ(s.q(1, 0), 2);
  EXPECT_EQ(s.v(1, 0), 4);
  EXPECT_EQ(s.a(0, 0), 5);
  EXPECT_EQ(s.tau(0, 0), 7);
  EXPECT_EQ(s.tau(1, 0), 8);
  EXPECT_EQ(s.tau(1, 1), -0.8);
  EXPECT_EQ(s.q(0, 1), 1.5);
  EXPECT_FALSE(s.t.has_value());
  EXPECT_EQ(s.lines, (std::vector<std::size_t>{4, 5}));
  EXPECT_EQ(s.ignored_columns, std::vector<std::string>{"current_j1"});
}

TEST(MeasuredSamples, WritingAndReadingGiveTheSameDoubles) {
  const Robot robot = arm7();
  const batch::MeasuredSamples s = batch::syntheticSamples(robot.model, syntheticOptions(50, 0.01));
  TempDir dir;
  batch::writeMeasuredSamples(dir / "s.csv", s, robot.model);
  const batch::MeasuredSamples back = batch::readMeasuredSamples(dir / "s.csv", robot.model);
  EXPECT_EQ(back.q, s.q);
  EXPECT_EQ(back.v, s.v);
  EXPECT_EQ(back.a, s.a);
  EXPECT_EQ(back.tau, s.tau);
  ASSERT_TRUE(back.t.has_value());
  EXPECT_EQ(*back.t, *s.t);
  EXPECT_EQ(back.lines.front(), 2u);
  EXPECT_EQ(back.source, (dir / "s.csv").string());
}

TEST(MeasuredSamples, ANonNumberNamesTheLineTheColumnAndTheText) {
  EXPECT_EQ(errorOf(std::string(kHeader) + "0,1,2,3,4,5,6,7,8\n0,1,2,3,4,5,6,7,abc\n"),
            "samples.csv:3: column tau_j2: 'abc' is not a number");
  // Comments and blank lines count as lines.
  EXPECT_EQ(errorOf(std::string("# note\n") + kHeader + "\n0,1,2,3,4,1.5.2,6,7,8\n"),
            "samples.csv:4: column a_j1: '1.5.2' is not a number");
  EXPECT_EQ(errorOf(std::string(kHeader) + "0,1,,3,4,5,6,7,8\n"), "samples.csv:2: column q_j2: is empty");
  EXPECT_EQ(errorOf(std::string(kHeader) + "0,1,2,3,4,5,6,7,1e999\n"),
            "samples.csv:2: column tau_j2: '1e999' is out of the range of a double");
  EXPECT_EQ(errorOf(std::string(kHeader) + "x,1,2,3,4,5,6,7,8\n"), "samples.csv:2: column t: 'x' is not a number");
}

TEST(MeasuredSamples, NanAndInfAreRejected) {
  EXPECT_EQ(errorOf(std::string(kHeader) + "0,nan,2,3,4,5,6,7,8\n"), "samples.csv:2: column q_j1: 'nan' is not finite");
  EXPECT_EQ(errorOf(std::string(kHeader) + "0,1,2,3,-inf,5,6,7,8\n"),
            "samples.csv:2: column v_j2: '-inf' is not finite");
}

TEST(MeasuredSamples, AWrongFieldCountNamesTheLine) {
  EXPECT_EQ(errorOf(std::string(kHeader) + "0,1,2,3,4,5,6,7,8\n0,1,2,3,4,5,6,7,8,9\n"),
            "samples.csv:3: 10 fields, the header (line 1) has 9");
  EXPECT_EQ(errorOf(std::string("# note\n") + kHeader + "0,1,2\n"),
            "samples.csv:3: 3 fields, the header (line 2) has 9");
}

TEST(MeasuredSamples, MissingColumnsAreListedByName) {
  EXPECT_EQ(errorOf("q_j1,q_j2,v_j1,a_j1,a_j2,tau_j1\n"),
            "samples.csv:1: the header lacks 2 columns of robot 'two': v_j2, tau_j2 "
            "(expected q_, v_, a_ and tau_ columns per joint)");
  EXPECT_EQ(errorOf("q_j1,q_j2,v_j1,v_j2,a_j1,a_j2,tau_j1,tau_j2,q_j1\n"),
            "samples.csv:1: column 'q_j1' is named twice in the header");
}

TEST(MeasuredSamples, EmptyFilesAreReported) {
  const std::string no_header =
      "samples.csv: no header row (the first line that is not blank or a # comment names the columns)";
  EXPECT_EQ(errorOf(""), no_header);
  EXPECT_EQ(errorOf("# only a comment\n\n"), no_header);
  EXPECT_EQ(errorOf(kHeader), "samples.csv:1: a header but no samples");
  EXPECT_THROW(batch::readMeasuredSamples("/nonexistent/samples.csv", twoJoints()), IdentificationError);
  EXPECT_THROW(batch::readMeasuredSamples("/", twoJoints()), IdentificationError);
}

TEST(MeasuredSamples, ColumnsForAFreeFlyerFollowTheCliLabels) {
  const Model floating = loadUrdfString(kTwoJoints, RootJoint::FreeFlyer);
  const std::vector<std::string> columns = batch::sampleColumns(floating);
  ASSERT_EQ(columns.size(), static_cast<std::size_t>(floating.nq + 3 * floating.nv));
  EXPECT_EQ(columns[0], "q_root_joint.x");
  EXPECT_EQ(columns[6], "q_root_joint.qw");
  EXPECT_EQ(columns[9], "v_root_joint.vx");
  EXPECT_EQ(columns.back(), "tau_j2");
}

}  // namespace
}  // namespace robodiff::testing
