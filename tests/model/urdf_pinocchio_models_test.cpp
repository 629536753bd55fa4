// The models of ../shared's robots against Pinocchio's (../shared/golden): the same
// joints in the same order, with the same parents, q/v layout, kinds and axes, and the
// same frames. Skips with a message where ../shared is absent.
#include "robodiff/model/urdf_loader.hpp"

#include <gtest/gtest.h>

#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/golden.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

struct PinocchioKind {
  JointType type;
  AxisKind axis;
  bool continuous;
};

PinocchioKind pinocchioKind(const std::string& name) {
  static const std::map<std::string, PinocchioKind> kinds = {
      {"JointModelRX", {JointType::Revolute, AxisKind::X, false}},
      {"JointModelRY", {JointType::Revolute, AxisKind::Y, false}},
      {"JointModelRZ", {JointType::Revolute, AxisKind::Z, false}},
      {"JointModelRevoluteUnaligned", {JointType::Revolute, AxisKind::Unaligned, false}},
      {"JointModelRUBX", {JointType::Revolute, AxisKind::X, true}},
      {"JointModelRUBY", {JointType::Revolute, AxisKind::Y, true}},
      {"JointModelRUBZ", {JointType::Revolute, AxisKind::Z, true}},
      {"JointModelRevoluteUnboundedUnaligned", {JointType::Revolute, AxisKind::Unaligned, true}},
      {"JointModelPX", {JointType::Prismatic, AxisKind::X, false}},
      {"JointModelPY", {JointType::Prismatic, AxisKind::Y, false}},
      {"JointModelPZ", {JointType::Prismatic, AxisKind::Z, false}},
      {"JointModelPrismaticUnaligned", {JointType::Prismatic, AxisKind::Unaligned, false}},
      {"JointModelFreeFlyer", {JointType::FreeFlyer, AxisKind::Unaligned, false}},
  };
  auto it = kinds.find(name);
  if (it == kinds.end()) throw std::runtime_error("unexpected Pinocchio joint model " + name);
  return it->second;
}

TEST(UrdfLoader, JointsAndFramesMatchPinocchio) {
  ROBODIFF_REQUIRE_SHARED(shared);
  for (const std::string& robot : testing::goldenNames()) {
    SCOPED_TRACE(robot);
    const nlohmann::json golden =
        nlohmann::json::parse(testing::readFile(shared / "golden" / (robot + ".json")));
    const bool free_flyer = golden["root_joint"] == "freeflyer";
    const Model m = loadUrdfFile((shared / golden["urdf"].get<std::string>()).string(),
                                 free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
    auto jointName = [&](int j) { return j < 0 ? std::string("universe") : m.joints[j].name; };

    EXPECT_EQ(m.nq, golden["nq"].get<int>());
    EXPECT_EQ(m.nv, golden["nv"].get<int>());
    std::vector<std::string> expected_joints;
    for (const auto& j : golden["joints"]) expected_joints.push_back(j["name"]);
    ASSERT_EQ(m.jointNames(), expected_joints);
    for (int j = 0; j < m.njoints(); ++j) {
      const auto& g = golden["joints"][j];
      const Joint& joint = m.joints[j];
      SCOPED_TRACE(joint.name);
      EXPECT_EQ(jointName(joint.parent), g["parent_joint"].get<std::string>());
      EXPECT_EQ(joint.idx_q, g["idx_q"].get<int>());
      EXPECT_EQ(joint.nq, g["nq"].get<int>());
      EXPECT_EQ(joint.idx_v, g["idx_v"].get<int>());
      EXPECT_EQ(joint.nv, g["nv"].get<int>());
      const PinocchioKind kind = pinocchioKind(g["type"]);
      EXPECT_EQ(joint.type, kind.type) << g["type"];
      if (joint.type != JointType::FreeFlyer) {
        EXPECT_EQ(joint.axis_kind, kind.axis) << g["type"];
        EXPECT_EQ(joint.continuous, kind.continuous) << g["type"];
      }
    }

    const auto& frames = golden["frames"];
    ASSERT_EQ(m.nframes(), static_cast<int>(frames.size()));
    for (int f = 0; f < m.nframes(); ++f) {
      const Frame& frame = m.frames[f];
      EXPECT_EQ(frame.name, frames[f]["name"].get<std::string>()) << "frame " << f;
      EXPECT_EQ(toString(frame.type), frames[f]["type"].get<std::string>()) << frame.name;
      EXPECT_EQ(jointName(frame.parent_joint), frames[f]["parent_joint"].get<std::string>()) << frame.name;
    }
  }
}

}  // namespace
}  // namespace robodiff
