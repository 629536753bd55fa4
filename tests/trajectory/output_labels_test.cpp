// The CSV header's names for output rows and columns: by joint coordinate where the
// function's outputs are per joint, by input for a derivative's columns, by number else.
#include <gtest/gtest.h>

#include "robodiff/batch/trajectory_table.hpp"
#include "support/cache_workspace.hpp"
#include "trajectory/trajectory_fixtures.hpp"

namespace robodiff::testing {
namespace {

std::vector<batch::AxisLabels> labelsOf(const Robot& robot, const char* spec_json, const TempDir& tmp) {
  const FunctionSpec spec = parseFunctionSpec(spec_json);
  const batch::BatchFunction f = robot.open(spec, batch::Backend::Interpreted, tmp / "cache");
  return batch::outputAxisLabels(robot.model, spec, f.inputs(), f.outputs());
}

TEST(OutputLabels, FloatingBaseRowsAndJacobianColumnsAreNamedByCoordinate) {
  TempDir tmp;
  const Robot quadruped("quadruped", true);
  const auto labels = labelsOf(
      quadruped, R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v"]}]})",
      tmp);
  ASSERT_EQ(labels.size(), 2u);
  const std::size_t nv = static_cast<std::size_t>(quadruped.model.nv);
  const std::string leg = quadruped.model.joints[1].name;
  ASSERT_EQ(labels[0].rows.size(), nv);
  EXPECT_EQ(labels[0].rows[0], "root_joint_vx");
  EXPECT_EQ(labels[0].rows[5], "root_joint_wz");
  EXPECT_EQ(labels[0].rows[6], leg);
  EXPECT_TRUE(labels[0].cols.empty());
  // q's columns are its nv tangent directions, then v's.
  ASSERT_EQ(labels[1].cols.size(), 2 * nv);
  EXPECT_EQ(labels[1].cols[0], "q_root_joint_vx");
  EXPECT_EQ(labels[1].cols[6], "q_" + leg);
  EXPECT_EQ(labels[1].cols[nv + 3], "v_root_joint_wx");
  EXPECT_EQ(labels[1].rows, labels[0].rows);
}

TEST(OutputLabels, AValueOfSizeNvThatIsNotPerJointIsNumbered) {
  TempDir tmp;
  const Robot arm("arm7");
  ASSERT_EQ(arm.model.nv, 7);  // fk's value has 7 entries too: position and quaternion
  const std::string frame = arm.model.frames.back().name;
  const std::string spec = R"({"function": "fk", "frame": ")" + frame +
                           R"(", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q"]}]})";
  const auto labels = labelsOf(arm, spec.c_str(), tmp);
  ASSERT_EQ(labels.size(), 2u);
  EXPECT_TRUE(labels[0].rows.empty());
  EXPECT_TRUE(labels[1].rows.empty());
  ASSERT_EQ(labels[1].cols.size(), 7u);
  EXPECT_EQ(labels[1].cols[0], "q_" + arm.model.joints[0].name);
}

TEST(OutputLabels, TheMassMatrixIsNamedBothWaysAndTheHeaderUsesTheLabels) {
  TempDir tmp;
  const Robot arm("arm7");
  const auto labels = labelsOf(arm, R"({"function": "crba", "outputs": [{"kind": "value"}]})", tmp);
  ASSERT_EQ(labels.size(), 1u);
  EXPECT_EQ(labels[0].rows, batch::dofNames(arm.model));
  EXPECT_EQ(labels[0].cols, labels[0].rows);
  const FunctionSpec spec = parseFunctionSpec(R"({"function": "crba", "outputs": [{"kind": "value"}]})");
  const batch::BatchFunction f = arm.open(spec, batch::Backend::Interpreted, tmp / "cache");
  const std::vector<std::string> names = batch::outputColumnNames(f.outputs(), labels);
  const std::string j0 = arm.model.joints[0].name, j1 = arm.model.joints[1].name;
  ASSERT_EQ(names.size(), 49u);
  EXPECT_EQ(names[1], "value_" + j0 + "_" + j1);
  EXPECT_EQ(names[7], "value_" + j1 + "_" + j0);
}

}  // namespace
}  // namespace robodiff::testing
