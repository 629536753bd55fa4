// core/dynamics against Pinocchio's values in ../shared/golden, for every robot, every
// sample and every quantity there, to 1e-9 relative.
#include <map>
#include <memory>

#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::GoldenRobot;
using testing::matricesAgree;

struct Loaded {
  GoldenRobot golden;
  Model model;
};

const Loaded& load(const std::filesystem::path& shared, const std::string& name) {
  static std::map<std::string, std::unique_ptr<Loaded>> cache;
  auto& slot = cache[name];
  if (!slot) {
    GoldenRobot g = testing::loadGolden(shared, name);
    Model m = loadUrdfFile(g.urdf.string(), g.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
    slot = std::make_unique<Loaded>(Loaded{std::move(g), std::move(m)});
  }
  return *slot;
}

class Golden : public ::testing::TestWithParam<std::string> {};

#define FOR_EACH_SAMPLE(body)                                                  \
  ROBODIFF_REQUIRE_SHARED(shared);                                             \
  const Loaded& robot = load(shared, GetParam());                              \
  const Model& model = robot.model;                                            \
  Data<double> data(model);                                                    \
  ASSERT_EQ(model.nq, robot.golden.nq);                                        \
  ASSERT_EQ(model.nv, robot.golden.nv);                                        \
  for (size_t s = 0; s < robot.golden.samples.size(); ++s) {                   \
    SCOPED_TRACE("sample " + std::to_string(s));                               \
    const auto& sample = robot.golden.samples[s];                              \
    body                                                                       \
  }

TEST_P(Golden, Rnea) {
  FOR_EACH_SAMPLE(EXPECT_TRUE(matricesAgree(rnea(model, data, sample.q, sample.v, sample.a), sample.tau));)
}

TEST_P(Golden, NonLinearEffects) {
  FOR_EACH_SAMPLE(EXPECT_TRUE(matricesAgree(nonLinearEffects(model, data, sample.q, sample.v), sample.nle));)
}

TEST_P(Golden, GeneralizedGravity) {
  FOR_EACH_SAMPLE(
      EXPECT_TRUE(matricesAgree(computeGeneralizedGravity(model, data, sample.q), sample.gravity_torque));)
}

TEST_P(Golden, Crba) {
  FOR_EACH_SAMPLE(EXPECT_TRUE(matricesAgree(crba(model, data, sample.q), sample.M));)
}

TEST_P(Golden, Aba) {
  FOR_EACH_SAMPLE(EXPECT_TRUE(matricesAgree(aba(model, data, sample.q, sample.v, sample.tau), sample.ddq));)
}

TEST_P(Golden, FramePlacements) {
  FOR_EACH_SAMPLE({
    forwardKinematics(model, data, sample.q);
    updateFramePlacements(model, data);
    ASSERT_EQ(static_cast<size_t>(model.nframes()), sample.frame_placements.size());
    for (const auto& [name, expected] : sample.frame_placements) {
      SCOPED_TRACE("frame " + name);
      int f = model.frameIndex(name);
      EXPECT_TRUE(matricesAgree(data.oMf[f].translation, expected.translation));
      EXPECT_TRUE(matricesAgree(data.oMf[f].rotation, expected.rotation));
    }
  })
}

TEST_P(Golden, FrameJacobianLocalWorldAligned) {
  FOR_EACH_SAMPLE({
    computeJointJacobians(model, data, sample.q);
    for (const auto& [name, expected] : sample.ee_jacobian_local_world_aligned) {
      SCOPED_TRACE("frame " + name);
      EXPECT_TRUE(matricesAgree(
          frameJacobian(model, data, model.frameIndex(name), ReferenceFrame::LocalWorldAligned), expected));
    }
  })
}

TEST_P(Golden, Regressor) {
  FOR_EACH_SAMPLE(
      EXPECT_TRUE(matricesAgree(jointTorqueRegressor(model, data, sample.q, sample.v, sample.a), sample.regressor));)
}

TEST_P(Golden, InertialParameters) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const Loaded& robot = load(shared, GetParam());
  EXPECT_TRUE(matricesAgree(inertialParameters(robot.model), robot.golden.inertial_parameters));
}

INSTANTIATE_TEST_SUITE_P(Robots, Golden, ::testing::ValuesIn(testing::goldenNames()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace robodiff
