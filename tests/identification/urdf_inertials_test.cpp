// The URDF written with identified inertials: loading it gives back exactly the
// parameters written (core/model merges the links again, core/spatial gives the
// parameters), merged links are zeroed with a note, everything outside the <inertial>
// elements is kept byte for byte, and parameters the loader would reject are refused
// naming the link.
#include <regex>

#include <gtest/gtest.h>

#include "identification_fixture.hpp"
#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/urdf_inertials.hpp"

namespace robodiff::testing {
namespace {

// The text without its <inertial> elements and the notes before them.
std::string withoutInertials(const std::string& text) {
  static const std::regex note(R"(<!-- robodiff identify:[^>]*-->\s*)");
  static const std::regex inertial(R"(<inertial>[\s\S]*?</inertial>)");
  return std::regex_replace(std::regex_replace(text, note, ""), inertial, "");
}

void expectSameParameters(const Eigen::VectorXd& got, const Eigen::VectorXd& want) {
  ASSERT_EQ(got.size(), want.size());
  for (Eigen::Index i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12 * (1 + std::abs(want[i]))) << i;
}

TEST(UrdfInertials, TheWrittenUrdfLoadsToTheWrittenParameters) {
  const Robot robot = arm7();
  const Eigen::VectorXd pi = batch::modelParameters(batch::perturbInertias(robot.model, 0.3, 17));
  const batch::UrdfRewrite out = batch::rewriteUrdfInertials(robot.urdf, "arm7.urdf", robot.model, pi);
  const Model reloaded = loadUrdfString(out.text, RootJoint::Fixed, "rewritten");
  expectSameParameters(batch::modelParameters(reloaded), pi);
  EXPECT_EQ(out.written, (std::vector<std::string>{"link1", "link2", "link3", "link4", "link5", "link6", "link7"}));
  EXPECT_EQ(out.zeroed, std::vector<std::string>{"tool"});  // fixed to link7: merged into its body
  EXPECT_NE(out.text.find("merged into the identified inertial of link 'link7'"), std::string::npos);
  // Kinematics, names, the base link's inertial outside the tree... all as they were.
  EXPECT_EQ(withoutInertials(out.text), withoutInertials(robot.urdf));
  EXPECT_NE(out.text.find("ixx=\"0.019421370104990072\""), std::string::npos);  // base_link, fixed to the world
}

TEST(UrdfInertials, ALinkWithoutInertialGetsOne) {
  const std::string urdf = R"(<robot name="r">
	<link name="base"/>
	<joint name="j1" type="continuous"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/></joint>
	<link name="l1"/>
	<joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/><origin xyz="0.2 0 0"/><axis xyz="0 1 0"/></joint>
	<link name="l2">
	  <visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
	</link>
</robot>)";
  const Model model = loadUrdfString(urdf);
  Eigen::VectorXd pi(20);
  pi << 2.0, 0.1, 0.02, -0.04, 0.03, 0.001, 0.04, -0.002, 0.003, 0.02,  //
      1.0, 0.05, 0.0, 0.01, 0.02, 0.0, 0.02, 0.0, 0.0, 0.01;
  const batch::UrdfRewrite out = batch::rewriteUrdfInertials(urdf, "r.urdf", model, pi);
  expectSameParameters(batch::modelParameters(loadUrdfString(out.text)), pi);
  EXPECT_NE(out.text.find("<link name=\"l1\">\n\t  <inertial>"), std::string::npos) << out.text;
  EXPECT_NE(out.text.find("<visual>"), std::string::npos);
}

TEST(UrdfInertials, ParametersTheLoaderWouldRejectAreRefusedNamingTheLink) {
  const Robot robot = arm7();
  Eigen::VectorXd pi = batch::modelParameters(robot.model);
  pi[20] = -0.5;  // the mass of link3
  try {
    batch::rewriteUrdfInertials(robot.urdf, "arm7.urdf", robot.model, pi);
    FAIL() << "no error";
  } catch (const batch::IdentificationError& e) {
    EXPECT_NE(std::string(e.what()).find("arm7.urdf:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("link 'link3'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("mass -0.5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("is not positive"), std::string::npos) << e.what();
  }
}

TEST(UrdfInertials, ALinkThatOnlyBreaksTheTriangleInequalityIsStillWritten) {
  // The URDF loader takes it (it checks mass and definiteness only); the report flags it.
  const Robot robot = arm7();
  Eigen::VectorXd pi = batch::modelParameters(robot.model);
  const Eigen::Matrix<double, 10, 1> body = pi.segment<10>(20);
  const batch::BodyInertial b = batch::inertialFromParameters(body);
  // Izz about the centre of mass raised past Ixx + Iyy: still positive definite.
  pi[29] += b.inertia(0, 0) + b.inertia(1, 1);
  ASSERT_FALSE(batch::inertialValidity(pi.segment<10>(20)).valid);
  const batch::UrdfRewrite out = batch::rewriteUrdfInertials(robot.urdf, "arm7.urdf", robot.model, pi);
  expectSameParameters(batch::modelParameters(loadUrdfString(out.text)), pi);
}

TEST(UrdfInertials, ConsistencyChecks) {
  Eigen::Matrix<double, 10, 1> p = batch::modelParameters(arm7().model).segment<10>(30);
  EXPECT_TRUE(batch::inertialValidity(p).valid) << batch::inertialValidity(p).message;
  // A rod along x: principal moments (0, L, L) are the limit of both positive definiteness
  // and the triangle inequality; consistent up to rounding, not strictly valid. A larger
  // moment breaks the triangle inequality.
  Eigen::Matrix<double, 10, 1> rod;
  rod << 1, 0, 0, 0, 0, 0, 1, 0, 0, 1;
  EXPECT_TRUE(batch::inertialValidity(rod).valid) << batch::inertialValidity(rod).message;
  EXPECT_FALSE(batch::checkBodyValidity(rod).valid);
  rod[9] = 3;
  EXPECT_NE(batch::inertialValidity(rod).message.find("triangle inequality"), std::string::npos);
  rod[4] = -1;
  EXPECT_NE(batch::inertialValidity(rod).message.find("not positive definite"), std::string::npos);
  rod[0] = 0;
  EXPECT_NE(batch::inertialValidity(rod).message.find("mass 0"), std::string::npos);
  // The inertial form: centre of mass and inertia about it.
  const batch::BodyInertial b = batch::inertialFromParameters(p);
  const Inertia<double> back{b.mass, b.com, b.inertia};
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(back.parameters()[i], p[i], 1e-14);
}

}  // namespace
}  // namespace robodiff::testing
