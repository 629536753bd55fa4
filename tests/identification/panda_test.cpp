// The Panda arm from ../shared (skipped when it is absent): its URDF masses and inertias
// perturbed (the truth), noisy torques, the identification recovers the base parameters
// within a few standard errors, and the identified URDF puts the hand and fingers (fixed
// to link 7) into link 7's inertial and reloads to the identified parameters.
#include <gtest/gtest.h>

#include "identification_fixture.hpp"
#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/urdf_inertials.hpp"

namespace robodiff::testing {
namespace {

TEST(PandaIdentification, RecoversThePerturbedTruth) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const Robot panda = loadRobot(shared / "robots/panda_arm_fixed_fingers.urdf");
  const Model truth = batch::perturbInertias(panda.model, 0.25, 8);
  const double sigma = 0.02;
  const batch::MeasuredSamples samples = batch::syntheticSamples(truth, syntheticOptions(1200, sigma, 4));
  const batch::IdentificationOptions options = interpretedOptions(0.25, false);
  const batch::IdentificationProblem problem =
      batch::prepareIdentification(panda.model, panda.urdf, panda.path.string(), false, samples, options);
  const batch::IdentificationResult result = batch::identifyLeastSquares(problem, options);
  const Eigen::VectorXd truth_base = problem.base.fromStandard(batch::modelParameters(truth));
  ASSERT_EQ(result.base_values.size(), truth_base.size());
  for (Eigen::Index k = 0; k < truth_base.size(); ++k)
    EXPECT_LE(std::abs(result.base_values[k] - truth_base[k]), 5 * result.base_std_errors[k])
        << problem.base.describe(static_cast<int>(k), problem.layout);
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(result.rms_held_out[j], sigma, 0.3 * sigma) << "joint " << j;

  const batch::IdentifiedBody& last = problem.layout.bodies.back();
  EXPECT_EQ(last.link, "panda_link7");
  EXPECT_EQ(last.merged_links.size(), 5u);  // link8, hand, tcp, two fingers
  // The written URDF reloads to the identified parameters; least squares may leave a body
  // that no URDF can hold (negative mass, indefinite inertia), and then the writer says which.
  std::string unwritable;
  for (std::size_t j = 0; j < result.bodies.size(); ++j) {
    const batch::BodyValidity& v = result.bodies[j].validity;
    if (!v.valid && (v.mass <= 0 || v.principal_moments[0] < 0) && unwritable.empty())
      unwritable = problem.layout.bodies[j].link;
  }
  if (!unwritable.empty()) {
    try {
      batch::rewriteUrdfInertials(panda.urdf, panda.path.string(), panda.model, result.parameters);
      FAIL() << "no error for link " << unwritable;
    } catch (const batch::IdentificationError& e) {
      EXPECT_NE(std::string(e.what()).find("link '" + unwritable + "'"), std::string::npos) << e.what();
    }
    return;
  }
  const batch::UrdfRewrite out =
      batch::rewriteUrdfInertials(panda.urdf, panda.path.string(), panda.model, result.parameters);
  EXPECT_EQ(out.zeroed.size(), 5u);
  const Eigen::VectorXd back = batch::modelParameters(loadUrdfString(out.text, RootJoint::Fixed, "rewritten"));
  for (Eigen::Index i = 0; i < back.size(); ++i)
    EXPECT_NEAR(back[i], result.parameters[i], 1e-12 * (1 + std::abs(result.parameters[i])));
}

}  // namespace
}  // namespace robodiff::testing
