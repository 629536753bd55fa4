// URDFs that would exhaust the stack or memory of the loading process: refused by the
// limit scan (ModelTooLarge naming the limit and the value) before any parser sees them,
// quickly and without a crash; and chains at the limits still load.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <chrono>
#include <string>

#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_limits.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff {
namespace {

// <robot name="r"><a><a>...</a></a></robot>, `depth` levels of <a> below the root.
std::string deeplyNested(int depth, bool closed = true) {
  std::string xml = "<robot name=\"r\"><link name=\"base\"/>";
  for (int i = 0; i < depth; ++i) xml += "<a>";
  if (closed)
    for (int i = 0; i < depth; ++i) xml += "</a>";
  return xml + "</robot>";
}

// A root link followed by `links` - 1 links, each joined to the previous one by a fixed
// joint; the last one hangs from a revolute joint so that the model has a moving body.
std::string fixedChain(int links) {
  const std::string inertial =
      "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/>"
      "</inertial>";
  std::string xml = "<robot name=\"chain\">\n<link name=\"l0\"/>\n";
  xml.reserve(static_cast<std::size_t>(links) * 200);
  for (int i = 1; i < links; ++i) {
    const bool last = i == links - 1;
    const std::string l = "l" + std::to_string(i);
    xml += "<link name=\"" + l + "\">" + inertial + "</link>\n";
    xml += "<joint name=\"j" + std::to_string(i) + "\" type=\"" + (last ? "revolute" : "fixed") +
           "\"><parent link=\"l" + std::to_string(i - 1) + "\"/><child link=\"" + l + "\"/>" +
           "<origin xyz=\"0 0 0.001\"/>" + (last ? "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>" : "") +
           "</joint>\n";
  }
  return xml + "</robot>\n";
}

// The ModelTooLarge that loading `xml` throws; fails the test when none is thrown.
ModelTooLarge tooLarge(const std::string& xml, const UrdfLimits& limits = {}) {
  try {
    loadUrdfString(xml, RootJoint::Fixed, "big.urdf", limits);
  } catch (const ModelTooLarge& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected ModelTooLarge, got: " << e.what();
  }
  ADD_FAILURE() << "expected ModelTooLarge, the URDF loaded";
  return ModelTooLarge("", "", 0, 0);
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST(UrdfLimits, HundredThousandNestedElementsAreRefusedWithoutCrashing) {
  const std::string xml = deeplyNested(100'000);
  const auto start = std::chrono::steady_clock::now();
  ModelTooLarge e = tooLarge(xml);
  EXPECT_LT(secondsSince(start), 1.0);
  EXPECT_EQ(e.limitName(), "max_depth");
  EXPECT_EQ(e.value(), 100'001u);  // the <a>s below the root
  EXPECT_STREQ(e.what(), "big.urdf: the URDF nests elements 100001 deep; the limit is max_depth = 64");
}

TEST(UrdfLimits, UnclosedNestingIsRefusedToo) {
  EXPECT_EQ(tooLarge(deeplyNested(100'000, false)).limitName(), "max_depth");
}

// Tags a parser would see are counted even where the parsers disagree about the text:
// TinyXML ends "<?pi" at the first '>' and takes '<' into an unquoted attribute value.
TEST(UrdfLimits, TagsThatSomeParserSeesAreCounted) {
  std::string pi_hidden = "<robot name=\"r\"><?pi ";
  for (int i = 0; i < 100; ++i) pi_hidden += "<a>";
  EXPECT_EQ(tooLarge(pi_hidden + "?></robot>").limitName(), "max_depth");
  std::string unquoted = "<robot name=\"r\">";
  for (int i = 0; i < 100; ++i) unquoted += "<a x=y<>";
  EXPECT_EQ(tooLarge(unquoted + "</robot>").limitName(), "max_depth");
}

TEST(UrdfLimits, NestingInsideCommentsCdataAndAttributesDoesNotCount) {
  std::string hidden = "<!-- ";
  for (int i = 0; i < 1000; ++i) hidden += "<a>";
  hidden += " --><![CDATA[";
  for (int i = 0; i < 1000; ++i) hidden += "<b>";
  hidden += "]]><?pi c c c ?>";
  std::string xml = fixedChain(3);
  xml.insert(xml.find("<link name=\"l0\"/>"), hidden + "<link name=\"x\" note='<d><d>' />");
  // Not refused for its size: loading fails later only for the unconnected link "x".
  try {
    loadUrdfString(xml, RootJoint::Fixed, "ok.urdf");
    ADD_FAILURE() << "the unconnected link should be reported";
  } catch (const ModelTooLarge& e) {
    ADD_FAILURE() << "refused as too large: " << e.what();
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("root"), std::string::npos) << e.what();
  }
}

TEST(UrdfLimits, SixteenMegabyteFixedJointChainIsRefusedQuickly) {
  std::string xml = fixedChain(65'000);
  ASSERT_GT(xml.size(), 15'000'000u);
  ASSERT_LT(xml.size(), 16u << 20);  // within max_bytes: another limit must catch it
  const auto start = std::chrono::steady_clock::now();
  ModelTooLarge e = tooLarge(xml);
  EXPECT_LT(secondsSince(start), 2.0);
  EXPECT_EQ(e.limitName(), "max_elements");
  EXPECT_NE(std::string(e.what()).find("the limit is max_elements = 400000"), std::string::npos) << e.what();
}

TEST(UrdfLimits, ChainOfFixedJointsAtTheLinkLimitLoads) {
  UrdfLimits limits;
  Model m = loadUrdfString(fixedChain(static_cast<int>(limits.max_links)), RootJoint::Fixed, "chain.urdf");
  EXPECT_EQ(m.njoints(), 1);
  EXPECT_EQ(m.nframes(), 1 + 2 * static_cast<int>(limits.max_links) - 1);
  EXPECT_NEAR(m.joints[0].placement.translation.z(), 0.001 * (limits.max_links - 1), 1e-9);
}

TEST(UrdfLimits, LinksAndJointsBeyondTheirLimits) {
  UrdfLimits limits;
  limits.max_links = 10;
  ModelTooLarge links = tooLarge(fixedChain(11), limits);
  EXPECT_EQ(links.limitName(), "max_links");
  EXPECT_STREQ(links.what(), "big.urdf: the URDF has 11 links; the limit is max_links = 10");
  limits.max_links = 100;
  limits.max_joints = 5;
  ModelTooLarge joints = tooLarge(fixedChain(11), limits);
  EXPECT_EQ(joints.limitName(), "max_joints");
  EXPECT_EQ(joints.value(), 10u);
}

TEST(UrdfLimits, TooManyBytes) {
  UrdfLimits limits;
  limits.max_bytes = 1000;
  ModelTooLarge e = tooLarge(fixedChain(20), limits);
  EXPECT_EQ(e.limitName(), "max_bytes");
  EXPECT_NE(std::string(e.what()).find("; the limit is max_bytes = 1000"), std::string::npos) << e.what();
}

TEST(UrdfLimits, LongNamesAndAttributeValues) {
  const std::string chain = fixedChain(3);
  std::string long_link = chain;
  long_link.replace(long_link.find("\"l2\""), 4, "\"" + std::string(10'000'000, 'n') + "\"");
  ModelTooLarge name = tooLarge(long_link);
  EXPECT_EQ(name.limitName(), "max_name_length");
  EXPECT_EQ(name.value(), 10'000'000u);
  EXPECT_NE(std::string(name.what()).find("big.urdf: line 5: a name of 10000000 characters (\"nnnn"),
            std::string::npos)
      << name.what();
  EXPECT_LT(std::string(name.what()).size(), 200u);  // the name is not echoed whole

  std::string long_tag = chain;
  long_tag.replace(long_tag.find("<link name=\"l0\"/>"), 0, "<" + std::string(300, 't') + "/>");
  EXPECT_EQ(tooLarge(long_tag).limitName(), "max_name_length");

  std::string long_value = chain;
  long_value.replace(long_value.find("xyz=\"0 0 0.001\""), 0, "note=\"" + std::string(5000, 'v') + "\" ");
  EXPECT_EQ(tooLarge(long_value).limitName(), "max_attribute_length");
}

TEST(UrdfLimits, TheLargestGeneratedRobotLoads) {
  GeneratorOptions options;
  options.joints = kMaxGeneratedJoints;
  Model m = loadUrdfString(generateRobotUrdf(options), RootJoint::FreeFlyer, "chain10000");
  EXPECT_EQ(m.njoints(), kMaxGeneratedJoints + 1);
}

}  // namespace
}  // namespace robodiff

namespace robodiff {
namespace {

void loadWithoutCoreDump(const std::string& xml, const UrdfLimits& limits) {
  rlimit no_core{};  // a core file of the overflowed stack takes seconds
  setrlimit(RLIMIT_CORE, &no_core);
  rlimit small_stack{1 << 20, 1 << 20};  // a thread's size, and quicker to overflow
  setrlimit(RLIMIT_STACK, &small_stack);
  loadUrdfString(xml, RootJoint::Fixed, "deep.urdf", limits);
}

// The problem the depth limit solves: with it lifted, the parsers recurse once per level
// and overflow the stack (SIGSEGV), in a child process here.
TEST(UrdfLimitsDeathTest, WithoutTheDepthLimitTheParsersOverflowTheStack) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  UrdfLimits unlimited;
  unlimited.max_depth = unlimited.max_elements = 1'000'000;
  const std::string xml = deeplyNested(100'000);
  EXPECT_DEATH(loadWithoutCoreDump(xml, unlimited), "");
}

}  // namespace
}  // namespace robodiff
