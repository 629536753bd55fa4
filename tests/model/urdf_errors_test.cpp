// Bad URDFs: every error is a ModelError whose message names the source, the line, the
// element (joint or link by name) and the offending value.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>

#include "robodiff/model/urdf_loader.hpp"

namespace robodiff {
namespace {

// A valid two-link arm. The cases below break one thing each; the markers they look
// for (e.g. `<mass value="1.5"/>`) occur exactly once.
const std::string kArm = R"(<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/>
    <child link="upper"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="2"/>
    <dynamics damping="0.1" friction="0.2"/>
  </joint>
  <link name="upper">
    <inertial>
      <origin xyz="0 0 0.2" rpy="0 0 0"/>
      <mass value="1.5"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.05"/>
    </inertial>
  </link>
</robot>
)";

// `text` with the single occurrence of `from` replaced by `to`.
std::string urdfWith(const std::string& text, const std::string& from, const std::string& to) {
  size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "marker '" << from << "' not found";
  if (at == std::string::npos) return text;
  EXPECT_EQ(text.find(from, at + 1), std::string::npos) << "marker '" << from << "' is not unique";
  return text.substr(0, at) + to + text.substr(at + from.size());
}

// 1-based line of the first occurrence of `needle` in `text`.
int lineOf(const std::string& text, const std::string& needle) {
  size_t at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << "'" << needle << "' not found";
  if (at == std::string::npos) return -1;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
}

std::string at(const std::string& xml, const std::string& needle) {
  return "bad.urdf:" + std::to_string(lineOf(xml, needle)) + ": ";
}

// The message of the ModelError that loading `xml` throws ("" and a failure if none).
std::string urdfErrorOf(const std::string& xml, RootJoint root = RootJoint::Fixed) {
  try {
    loadUrdfString(xml, root, "bad.urdf");
  } catch (const ModelError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected a ModelError, got another exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected a ModelError, the URDF loaded:\n" << xml;
  return "";
}

::testing::AssertionResult urdfMentions(const std::string& message, std::initializer_list<std::string> parts) {
  for (const std::string& part : parts)
    if (message.find(part) == std::string::npos)
      return ::testing::AssertionFailure()
             << "message \"" << message << "\" does not contain \"" << part << "\"";
  return ::testing::AssertionSuccess();
}

TEST(UrdfErrors, TheBaselineArmLoads) {
  Model m = loadUrdfString(kArm, RootJoint::Fixed, "bad.urdf");
  EXPECT_EQ(m.njoints(), 1);
  EXPECT_EQ(m.joints[0].name, "shoulder");
}

// --- XML structure -------------------------------------------------------------------

TEST(UrdfErrors, MalformedXmlNamesSourceAndLine) {
  // <axis> left open: the parser finds </joint> where </axis> should be.
  std::string xml = urdfWith(kArm, R"(<axis xyz="0 0 1"/>)", R"(<axis xyz="0 0 1">)");
  std::string msg = urdfErrorOf(xml);
  EXPECT_TRUE(urdfMentions(msg, {"bad.urdf:" + std::to_string(lineOf(xml, "</joint>")) + ":", "malformed XML"}));
}

TEST(UrdfErrors, MalformedAttributeNamesItsLine) {
  std::string xml = urdfWith(kArm, R"(<mass value="1.5"/>)", R"(<mass value="1.5" value="2"/>)");
  EXPECT_TRUE(
      urdfMentions(urdfErrorOf(xml), {"bad.urdf:" + std::to_string(lineOf(xml, "<mass")) + ":", "malformed XML"}));
}

TEST(UrdfErrors, EmptyDocument) {
  std::string msg = urdfErrorOf("");
  EXPECT_TRUE(urdfMentions(msg, {"bad.urdf", "malformed XML", "empty"}));
  EXPECT_EQ(msg.find("bad.urdf:0"), std::string::npos) << msg;  // no made-up line 0
}

TEST(UrdfErrors, DocumentWithoutElements) {
  std::string msg = urdfErrorOf("<?xml version=\"1.0\"?>\n<!-- nothing here -->\n");
  EXPECT_TRUE(urdfMentions(msg, {"bad.urdf", "no <robot> element"}));
}

TEST(UrdfErrors, RootElementIsNotRobot) {
  std::string xml = "<?xml version=\"1.0\"?>\n<model name=\"arm\">\n  <link name=\"base\"/>\n</model>\n";
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {"bad.urdf:2: ", "<model>", "expected <robot>"}));
}

TEST(UrdfErrors, NoLinks) {
  std::string xml = "<?xml version=\"1.0\"?>\n\n<robot name=\"empty\">\n</robot>\n";
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {"bad.urdf:3: ", "no <link>"}));
}

TEST(UrdfErrors, NoRootLinkBecauseOfACycle) {
  std::string xml = R"(<robot name="loop">
  <link name="a"/>
  <link name="b"/>
  <joint name="a_to_b" type="fixed"><parent link="a"/><child link="b"/></joint>
  <joint name="b_to_a" type="fixed"><parent link="b"/><child link="a"/></joint>
</robot>)";
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {"bad.urdf:1: ", "no root link", "cycle"}));
}

TEST(UrdfErrors, CycleBesideTheTree) {
  std::string xml = urdfWith(kArm, "</robot>", R"(<link name="p"/>
  <link name="q"/>
  <joint name="p_to_q" type="fixed"><parent link="p"/><child link="q"/></joint>
  <joint name="q_to_p" type="fixed"><parent link="q"/><child link="p"/></joint>
</robot>)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<link name=\"p\"/>"), "link 'p'", "not reachable", "'base'"}));
}

TEST(UrdfErrors, SeveralRootsAreAllNamed) {
  std::string xml = urdfWith(kArm, "</robot>", "<link name=\"orphan\"/>\n</robot>");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<robot"), "several root links", "'base'", "'orphan'"}));
}

// --- joints and links ------------------------------------------------------------------

TEST(UrdfErrors, JointWithoutParent) {
  std::string xml = urdfWith(kArm, "<parent link=\"base\"/>", "");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint name=\"shoulder\""), "joint 'shoulder'", "<parent"}));
}

TEST(UrdfErrors, JointWithoutChild) {
  std::string xml = urdfWith(kArm, "<child link=\"upper\"/>", "<child/>");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint name=\"shoulder\""), "joint 'shoulder'", "<child"}));
}

TEST(UrdfErrors, ParentLinkNotDefined) {
  std::string xml = urdfWith(kArm, "<parent link=\"base\"/>", "<parent link=\"chassis\"/>");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint name=\"shoulder\""), "joint 'shoulder'",
                                      "parent link 'chassis'", "not defined"}));
}

TEST(UrdfErrors, ChildLinkNotDefined) {
  std::string xml = urdfWith(kArm, "<child link=\"upper\"/>", "<child link=\"uper\"/>");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint name=\"shoulder\""), "joint 'shoulder'",
                                      "child link 'uper'", "not defined"}));
}

TEST(UrdfErrors, JointIsItsOwnParent) {
  std::string xml = urdfWith(kArm, "<child link=\"upper\"/>", "<child link=\"base\"/>");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint name=\"shoulder\""), "joint 'shoulder'", "'base'"}));
}

TEST(UrdfErrors, DuplicateLinkName) {
  std::string xml = urdfWith(kArm, "</robot>", "  <link name=\"upper\"/>\n</robot>");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<link name=\"upper\"/>"), "duplicate link name 'upper'"}));
}

TEST(UrdfErrors, DuplicateJointName) {
  std::string xml = urdfWith(kArm, "</robot>", R"(  <link name="tool"/>
  <joint name="shoulder" type="fixed"><parent link="upper"/><child link="tool"/></joint>
</robot>)");
  EXPECT_TRUE(urdfMentions(
      urdfErrorOf(xml), {at(xml, "<joint name=\"shoulder\" type=\"fixed\""), "duplicate joint name 'shoulder'"}));
}

TEST(UrdfErrors, LinkThatIsTheChildOfTwoJoints) {
  std::string xml =
      urdfWith(kArm, "</robot>",
           R"(  <joint name="elbow" type="fixed"><parent link="base"/><child link="upper"/></joint>
</robot>)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint name=\"elbow\""), "joint 'elbow'", "link 'upper'",
                                      "already the child of joint 'shoulder'"}));
}

TEST(UrdfErrors, JointWithoutName) {
  std::string xml = urdfWith(kArm, "<joint name=\"shoulder\" type=\"revolute\">", "<joint type=\"revolute\">");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint type"), "<joint> without a name"}));
}

// --- numbers ---------------------------------------------------------------------------

TEST(UrdfErrors, NanInJointOrigin) {
  std::string xml = urdfWith(kArm, R"(<origin xyz="0 0 0.1")", R"(<origin xyz="0 nan 0.1")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "nan"), "joint 'shoulder'", "xyz=\"0 nan 0.1\"", "'nan'",
                                      "not a finite number"}));
}

TEST(UrdfErrors, InfInJointRpy) {
  std::string xml = urdfWith(kArm, R"(rpy="0 0 0"/>
    <axis)",
                         R"(rpy="0 -inf 0"/>
    <axis)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "-inf"), "joint 'shoulder'", "'-inf'", "not a finite number"}));
}

TEST(UrdfErrors, InfInInertialOrigin) {
  std::string xml = urdfWith(kArm, R"(<origin xyz="0 0 0.2")", R"(<origin xyz="0 0 inf")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "inf"), "link 'upper'", "'inf'", "not a finite number"}));
}

TEST(UrdfErrors, OverflowingNumberIsNotFinite) {
  std::string xml = urdfWith(kArm, R"(<origin xyz="0 0 0.2")", R"(<origin xyz="0 0 1e999")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "1e999"), "link 'upper'", "'1e999'", "not a finite number"}));
}

TEST(UrdfErrors, NanMass) {
  std::string xml = urdfWith(kArm, R"(<mass value="1.5"/>)", R"(<mass value="NaN"/>)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml),
                       {at(xml, "<mass"), "link 'upper'", "<mass value=\"NaN\">", "not a finite number"}));
}

TEST(UrdfErrors, InfInInertia) {
  std::string xml = urdfWith(kArm, R"(izz="0.05")", R"(izz="inf")");
  EXPECT_TRUE(
      urdfMentions(urdfErrorOf(xml), {at(xml, "<inertia "), "link 'upper'", "izz=\"inf\"", "not a finite number"}));
}

TEST(UrdfErrors, NanInAxisAndLimit) {
  std::string axis = urdfWith(kArm, R"(<axis xyz="0 0 1"/>)", R"(<axis xyz="0 0 nan"/>)");
  EXPECT_TRUE(
      urdfMentions(urdfErrorOf(axis), {at(axis, "<axis"), "joint 'shoulder'", "'nan'", "not a finite number"}));
  std::string limit = urdfWith(kArm, R"(upper="1")", R"(upper="nan")");
  EXPECT_TRUE(
      urdfMentions(urdfErrorOf(limit), {at(limit, "<limit"), "joint 'shoulder'", "upper=\"nan\"", "not a finite"}));
  std::string damping = urdfWith(kArm, R"(damping="0.1")", R"(damping="inf")");
  EXPECT_TRUE(
      urdfMentions(urdfErrorOf(damping), {at(damping, "<dynamics"), "joint 'shoulder'", "'inf'", "not a finite"}));
}

TEST(UrdfErrors, NonNumberToken) {
  std::string xml = urdfWith(kArm, R"(<origin xyz="0 0 0.1")", R"(<origin xyz="0 zero 0.1")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "zero"), "joint 'shoulder'", "'zero' is not a number"}));
  std::string mass = urdfWith(kArm, R"(<mass value="1.5"/>)", R"(<mass value="1.5kg"/>)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(mass), {at(mass, "<mass"), "link 'upper'", "'1.5kg' is not a number"}));
}

// urdfdom reads numbers in the C locale and rejects hexadecimal floats; the check
// before it must agree, or the error would come from urdfdom, without a line.
TEST(UrdfErrors, HexadecimalFloatIsNotANumber) {
  std::string xml = urdfWith(kArm, R"(<origin xyz="0 0 0.1")", R"(<origin xyz="0 0x1p-3 0.1")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "0x1p-3"), "joint 'shoulder'", "'0x1p-3' is not a number"}));
}

TEST(UrdfErrors, WrongCountOfNumbers) {
  std::string two = urdfWith(kArm, R"(<origin xyz="0 0 0.1")", R"(<origin xyz="0 0.1")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(two), {at(two, "<origin xyz=\"0 0.1\""), "joint 'shoulder'", "xyz=\"0 0.1\"",
                                      "expected 3 number(s), found 2"}));
  std::string four = urdfWith(kArm, R"(<axis xyz="0 0 1"/>)", R"(<axis xyz="0 0 1 0"/>)");
  EXPECT_TRUE(
      urdfMentions(urdfErrorOf(four), {at(four, "<axis"), "joint 'shoulder'", "expected 3 number(s), found 4"}));
  std::string mass = urdfWith(kArm, R"(<mass value="1.5"/>)", R"(<mass value="1.5 2"/>)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(mass), {at(mass, "<mass"), "link 'upper'", "expected 1 number(s), found 2"}));
}

TEST(UrdfErrors, MissingInertiaComponent) {
  std::string xml = urdfWith(kArm, R"( iyz="0")", "");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<inertia "), "link 'upper'", "'iyz'"}));
}

// --- physical validity -----------------------------------------------------------------

TEST(UrdfErrors, NegativeMass) {
  std::string xml = urdfWith(kArm, R"(<mass value="1.5"/>)", R"(<mass value="-1.5"/>)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<mass"), "link 'upper'", "negative mass -1.5"}));
}

TEST(UrdfErrors, InertiaNotPositiveSemiDefinite) {
  // Positive diagonal, but |ixy| > ixx, iyy: eigenvalues 0.1 +- 0.3 (one negative).
  std::string xml = urdfWith(kArm, R"(ixy="0")", R"(ixy="0.3")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml),
                       {at(xml, "<inertia "), "link 'upper'", "ixy=0.3", "not positive semi-definite"}));
  std::string negative = urdfWith(kArm, R"(ixx="0.1")", R"(ixx="-0.1")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(negative), {at(negative, "<inertia "), "link 'upper'", "ixx=-0.1",
                                           "not positive semi-definite"}));
}

TEST(UrdfErrors, ZeroMassAndZeroInertiaAreAccepted) {
  std::string xml = urdfWith(urdfWith(kArm, R"(<mass value="1.5"/>)", R"(<mass value="0"/>)"),
                         R"(ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.05")",
                         R"(ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0")");
  EXPECT_NO_THROW(loadUrdfString(xml));
}

TEST(UrdfErrors, ZeroAxis) {
  std::string xml = urdfWith(kArm, R"(<axis xyz="0 0 1"/>)", R"(<axis xyz="0 0 0"/>)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<axis"), "joint 'shoulder'", "zero axis", "\"0 0 0\""}));
}

TEST(UrdfErrors, AxisWithoutXyz) {
  std::string xml = urdfWith(kArm, R"(<axis xyz="0 0 1"/>)", R"(<axis/>)");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<axis"), "joint 'shoulder'", "'xyz'"}));
}

// --- unsupported and incomplete joints ---------------------------------------------------

TEST(UrdfErrors, MimicJoint) {
  std::string xml =
      urdfWith(kArm, "    <dynamics", "    <mimic joint=\"wrist\" multiplier=\"2\"/>\n    <dynamics");
  EXPECT_TRUE(
      urdfMentions(urdfErrorOf(xml), {at(xml, "<mimic"), "joint 'shoulder'", "mimic", "\"wrist\"", "not supported"}));
}

TEST(UrdfErrors, PlanarJoint) {
  std::string xml = urdfWith(kArm, R"(type="revolute")", R"(type="planar")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint"), "joint 'shoulder'", "'planar'", "not supported"}));
}

TEST(UrdfErrors, FloatingJointInsideTheTree) {
  std::string xml = urdfWith(kArm, R"(type="revolute")", R"(type="floating")");
  // Not even with a free-flyer root: the floating base is the caller's option, not a joint.
  for (RootJoint root : {RootJoint::Fixed, RootJoint::FreeFlyer})
    EXPECT_TRUE(
        urdfMentions(urdfErrorOf(xml, root), {at(xml, "<joint"), "joint 'shoulder'", "'floating'", "not supported"}));
}

TEST(UrdfErrors, UnknownJointType) {
  std::string xml = urdfWith(kArm, R"(type="revolute")", R"(type="ball")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint"), "joint 'shoulder'", "unknown joint type 'ball'"}));
}

TEST(UrdfErrors, JointWithoutType) {
  std::string xml = urdfWith(kArm, R"( type="revolute")", "");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint"), "joint 'shoulder'", "'type'"}));
}

TEST(UrdfErrors, RevoluteWithoutLimit) {
  std::string xml = urdfWith(kArm, R"(<limit lower="-1" upper="1" effort="10" velocity="2"/>)", "");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint"), "joint 'shoulder'", "revolute", "<limit>"}));
}

TEST(UrdfErrors, PrismaticWithoutLimit) {
  std::string xml = urdfWith(urdfWith(kArm, R"(<limit lower="-1" upper="1" effort="10" velocity="2"/>)", ""),
                         R"(type="revolute")", R"(type="prismatic")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<joint"), "joint 'shoulder'", "prismatic", "<limit>"}));
}

TEST(UrdfErrors, LowerLimitAboveUpper) {
  std::string xml = urdfWith(kArm, R"(lower="-1" upper="1")", R"(lower="1.25" upper="-0.5")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<limit"), "joint 'shoulder'", "lower 1.25", "upper -0.5"}));
}

TEST(UrdfErrors, LimitWithoutEffortOrVelocity) {
  std::string effort = urdfWith(kArm, R"( effort="10")", "");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(effort), {at(effort, "<limit"), "joint 'shoulder'", "'effort'"}));
  // urdfdom requires both on a continuous joint's <limit> too.
  std::string velocity =
      urdfWith(urdfWith(kArm, R"( velocity="2")", ""), R"(type="revolute")", R"(type="continuous")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(velocity), {at(velocity, "<limit"), "joint 'shoulder'", "'velocity'"}));
}

TEST(UrdfErrors, NegativeEffortOrVelocity) {
  std::string effort = urdfWith(kArm, R"(effort="10")", R"(effort="-10")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(effort), {at(effort, "<limit"), "joint 'shoulder'", "effort -10"}));
  std::string velocity = urdfWith(kArm, R"(velocity="2")", R"(velocity="-2")");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(velocity), {at(velocity, "<limit"), "joint 'shoulder'", "velocity -2"}));
}

TEST(UrdfErrors, EmptyDynamics) {
  std::string xml = urdfWith(kArm, R"(<dynamics damping="0.1" friction="0.2"/>)", "<dynamics/>");
  EXPECT_TRUE(urdfMentions(urdfErrorOf(xml), {at(xml, "<dynamics"), "joint 'shoulder'", "damping", "friction"}));
}

// --- sources -------------------------------------------------------------------------

TEST(UrdfErrors, DefaultSourceNameIsString) {
  std::string xml = urdfWith(kArm, R"(<mass value="1.5"/>)", R"(<mass value="-2"/>)");
  try {
    loadUrdfString(xml);
    FAIL() << "no ModelError";
  } catch (const ModelError& e) {
    EXPECT_TRUE(
        urdfMentions(e.what(), {"<string>:" + std::to_string(lineOf(xml, "<mass")) + ": ", "negative mass -2"}));
  }
}

class TempFile {
 public:
  explicit TempFile(const std::string& text) {
    path_ = std::filesystem::temp_directory_path() / ("robodiff_urdf_errors_" + std::to_string(::getpid()) +
                                                      "_" + std::to_string(counter_++) + ".urdf");
    std::ofstream(path_) << text;
  }
  ~TempFile() { std::filesystem::remove(path_); }
  std::string path() const { return path_.string(); }

 private:
  static inline int counter_ = 0;
  std::filesystem::path path_;
};

TEST(UrdfErrors, FileErrorNamesThePathAndLine) {
  std::string xml = urdfWith(kArm, R"(<axis xyz="0 0 1"/>)", R"(<axis xyz="0 0 0"/>)");
  TempFile file(xml);
  try {
    loadUrdfFile(file.path());
    FAIL() << "no ModelError";
  } catch (const ModelError& e) {
    EXPECT_TRUE(urdfMentions(e.what(), {file.path() + ":" + std::to_string(lineOf(xml, "<axis")) + ": ",
                                    "joint 'shoulder'", "zero axis"}));
  }
}

TEST(UrdfErrors, GoodFileLoads) {
  TempFile file(kArm);
  Model m = loadUrdfFile(file.path(), RootJoint::FreeFlyer);
  EXPECT_EQ(m.nq, 8);
  EXPECT_EQ(m.nv, 7);
}

TEST(UrdfErrors, NonexistentFileNamesThePath) {
  const std::string path = "/nonexistent/robodiff/no_such_robot.urdf";
  try {
    loadUrdfFile(path);
    FAIL() << "no ModelError";
  } catch (const ModelError& e) {
    EXPECT_TRUE(urdfMentions(e.what(), {path, "cannot open"}));
  }
}

TEST(UrdfErrors, DirectoryIsNotAUrdf) {
  const std::string path = std::filesystem::temp_directory_path().string();
  try {
    loadUrdfFile(path);
    FAIL() << "no ModelError";
  } catch (const ModelError& e) {
    EXPECT_TRUE(urdfMentions(e.what(), {path + ": ", "directory"}));
  }
}

}  // namespace
}  // namespace robodiff
