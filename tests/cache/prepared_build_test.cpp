// The cache key's recipe (cache::prepareBuild): the same robot written differently gets
// the same key, and everything that changes the library's bytes changes it.
#include <regex>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/codegen/compiler.hpp"
#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/test_paths.hpp"

namespace robodiff::cache {
namespace {

using nlohmann::json;

std::string arm7UrdfText() { return testing::readFile(testing::sourceDir() / "examples/robots/arm7.urdf"); }

// examples/specs/rnea_jacobian.json with the given build options.
std::string rneaJacobianSpecText(const std::string& optimization = "O0", bool native = false) {
  json spec = json::parse(testing::readFile(testing::sourceDir() / "examples/specs/rnea_jacobian.json"));
  spec["build"] = {{"optimization", optimization}, {"march_native", native}};
  return spec.dump();
}

PreparedBuild prepareArm(const std::string& urdf, const std::string& spec, const std::string& name = "") {
  const Model model = loadUrdfString(urdf, RootJoint::Fixed, "arm7.urdf");
  return prepareBuild(model, canonicalHash(model), parseFunctionSpec(spec, "spec"), name, "");
}

bool includes(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(PreparedBuild, TheSameRobotWrittenDifferentlyHasTheSameKey) {
  const std::string urdf = arm7UrdfText();
  std::string reformatted = std::regex_replace(urdf, std::regex("\n"), "\n\n    ");
  reformatted = std::regex_replace(reformatted, std::regex("/>"), "   />");
  ASSERT_NE(reformatted, urdf);
  const PreparedBuild a = prepareArm(urdf, rneaJacobianSpecText());
  const PreparedBuild b = prepareArm(reformatted, rneaJacobianSpecText());
  EXPECT_EQ(a.key, b.key);
  EXPECT_TRUE(isCacheKey(a.key)) << a.key;
}

TEST(PreparedBuild, AChangedMassChangesTheKey) {
  const std::string urdf = arm7UrdfText();
  const std::string heavier = std::regex_replace(urdf, std::regex("mass value=\"2.3056640625\""), "mass value=\"2.7\"",
                                                 std::regex_constants::format_first_only);
  ASSERT_NE(heavier, urdf) << "arm7.urdf changed: pick another mass to edit";
  EXPECT_NE(prepareArm(urdf, rneaJacobianSpecText()).key, prepareArm(heavier, rneaJacobianSpecText()).key);
}

TEST(PreparedBuild, BuildOptionsAndTheFunctionNameChangeTheKey) {
  const std::string urdf = arm7UrdfText();
  const PreparedBuild base = prepareArm(urdf, rneaJacobianSpecText("O0"));
  EXPECT_NE(base.key, prepareArm(urdf, rneaJacobianSpecText("O1")).key) << "optimisation level";
  EXPECT_NE(base.key, prepareArm(urdf, rneaJacobianSpecText("O0", true)).key) << "-march=native";
  EXPECT_NE(base.key, prepareArm(urdf, rneaJacobianSpecText("O0"), "arm_rnea").key) << "the C name";
  EXPECT_EQ(base.key, prepareArm(urdf, rneaJacobianSpecText("O0")).key) << "the key is not deterministic";

  EXPECT_EQ(base.info.robot, "arm7");
  EXPECT_EQ(base.info.function, "rnea");
  EXPECT_EQ(prepareArm(urdf, rneaJacobianSpecText("O0"), "arm_rnea").info.function, "arm_rnea");
  EXPECT_EQ(base.info.model_hash, base.identity.model_hash);
  EXPECT_EQ(base.info.spec, base.identity.spec);
  EXPECT_TRUE(includes(base.info.compiler, base.identity.compiler + " -O0")) << base.info.compiler;
  EXPECT_TRUE(includes(base.identity.generator, codegen::kGeneratorVersion)) << base.identity.generator;
  EXPECT_EQ(base.key, base.identity.key());
}

// The hash is the caller's (computed once where the model was loaded): it is what the
// key and the index row carry, and what the library's description will say.
TEST(PreparedBuild, TheModelHashIsTakenAsGiven) {
  const Model model = loadUrdfString(arm7UrdfText(), RootJoint::Fixed, "arm7.urdf");
  const FunctionSpec spec = parseFunctionSpec(rneaJacobianSpecText(), "spec");
  const PreparedBuild right = prepareBuild(model, canonicalHash(model), spec, "", "");
  const PreparedBuild other = prepareBuild(model, std::string(64, 'a'), spec, "", "");
  EXPECT_EQ(right.identity.model_hash, canonicalHash(model));
  EXPECT_EQ(right.options.model_hash, canonicalHash(model));
  EXPECT_EQ(other.info.model_hash, std::string(64, 'a'));
  EXPECT_NE(right.key, other.key);
}

// A build host compiling for a robot's x86-64 level: the level, not this CPU, is in the
// key and the flags, and the index row records it for the loader's check.
TEST(PreparedBuild, ATargetLevelIsInTheKeyAndTheEntry) {
  const std::string urdf = arm7UrdfText();
  json spec = json::parse(rneaJacobianSpecText());
  spec["build"] = {{"target", "x86-64-v3"}};
  const PreparedBuild level = prepareArm(urdf, spec.dump());
  const PreparedBuild generic = prepareArm(urdf, rneaJacobianSpecText("O2", false));
  const PreparedBuild native = prepareArm(urdf, rneaJacobianSpecText("O2", true));
  EXPECT_NE(level.key, generic.key);
  EXPECT_NE(level.key, native.key);
  EXPECT_TRUE(includes(level.identity.target_cpu, "x86-64-v3")) << level.identity.target_cpu;
  EXPECT_FALSE(includes(level.identity.target_cpu, "vendor")) << "the build host's CPU leaked into the key";
  EXPECT_TRUE(includes(level.info.compiler, "-march=x86-64-v3 -mtune=generic")) << level.info.compiler;
  EXPECT_TRUE(level.info.compiler.ends_with(" target=x86-64-v3")) << level.info.compiler;
  EXPECT_TRUE(generic.info.compiler.ends_with(" target=generic")) << generic.info.compiler;
  EXPECT_TRUE(native.info.compiler.ends_with(" target=" + targetLabel(true))) << native.info.compiler;
}

}  // namespace
}  // namespace robodiff::cache
