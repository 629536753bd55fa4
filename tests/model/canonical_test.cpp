// The canonical form and its SHA-256, the model's identity in the cache: equal for the
// same robot however the URDF is spelled, different whenever the dynamics or the
// interface (names, frames, limits, root) change.
#include "robodiff/model/canonical.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "robodiff/model/urdf_loader.hpp"

namespace robodiff {
namespace {

// A leg (hip, knee, a foot fixed to the shin) and a slider carrying a wheel: revolute,
// prismatic, continuous and fixed joints, rotated inertial frames, dynamics. The
// values that the cases below change occur once each.
const std::string kRobot = R"(<?xml version="1.0"?>
<robot name="canon">
  <link name="base">
    <inertial>
      <origin xyz="0 0 0.05"/>
      <mass value="4"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>
    </inertial>
  </link>
  <joint name="hip" type="revolute">
    <parent link="base"/>
    <child link="thigh"/>
    <origin xyz="0 0.1 0" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" effort="80" velocity="5"/>
    <dynamics damping="0.2" friction="0.1"/>
  </joint>
  <link name="thigh">
    <inertial>
      <origin xyz="0 0 -0.2" rpy="0.1 0 0"/>
      <mass value="2.5"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.005"/>
    </inertial>
  </link>
  <joint name="knee" type="revolute">
    <parent link="thigh"/>
    <child link="shin"/>
    <origin xyz="0 0 -0.4"/>
    <axis xyz="0 0.6 0.8"/>
    <limit lower="0" upper="2.5" effort="60" velocity="6"/>
  </joint>
  <link name="shin">
    <inertial>
      <origin xyz="0 0 -0.25"/>
      <mass value="1.5"/>
      <inertia ixx="0.015" ixy="0" ixz="0" iyy="0.015" iyz="0" izz="0.003"/>
    </inertial>
  </link>
  <joint name="ankle" type="fixed">
    <parent link="shin"/>
    <child link="foot"/>
    <origin xyz="0 0 -0.45" rpy="0 0.3 0"/>
  </joint>
  <link name="foot">
    <inertial>
      <origin xyz="0.05 0 -0.02"/>
      <mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/>
    </inertial>
  </link>
  <joint name="slider" type="prismatic">
    <parent link="base"/>
    <child link="carriage"/>
    <origin xyz="0.3 0 0"/>
    <axis xyz="1 0 0"/>
    <limit lower="-0.1" upper="0.1" effort="200" velocity="0.7"/>
  </joint>
  <link name="carriage">
    <inertial>
      <mass value="0.8"/>
      <inertia ixx="0.0011" ixy="0" ixz="0" iyy="0.0012" iyz="0" izz="0.0013"/>
    </inertial>
  </link>
  <joint name="wheel" type="continuous">
    <parent link="carriage"/>
    <child link="rim"/>
    <axis xyz="0 0 1"/>
  </joint>
  <link name="rim">
    <inertial>
      <mass value="0.3"/>
      <inertia ixx="0.0004" ixy="0" ixz="0" iyy="0.0004" iyz="0" izz="0.0007"/>
    </inertial>
  </link>
</robot>
)";

// The same robot with the links and joints in another order, the elements inside each
// joint and inertial shuffled, attributes in another order, and no XML declaration.
const std::string kReordered = R"(<robot name="canon">
  <joint type="continuous" name="wheel">
    <axis xyz="0 0 1"/>
    <child link="rim"/>
    <parent link="carriage"/>
  </joint>
  <link name="rim">
    <inertial>
      <inertia izz="0.0007" iyz="0" iyy="0.0004" ixz="0" ixy="0" ixx="0.0004"/>
      <mass value="0.3"/>
    </inertial>
  </link>
  <link name="foot">
    <inertial>
      <mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/>
      <origin xyz="0.05 0 -0.02"/>
    </inertial>
  </link>
  <joint name="slider" type="prismatic">
    <limit velocity="0.7" effort="200" upper="0.1" lower="-0.1"/>
    <axis xyz="1 0 0"/>
    <origin xyz="0.3 0 0"/>
    <child link="carriage"/>
    <parent link="base"/>
  </joint>
  <joint name="knee" type="revolute">
    <limit upper="2.5" lower="0" velocity="6" effort="60"/>
    <child link="shin"/>
    <axis xyz="0 0.6 0.8"/>
    <parent link="thigh"/>
    <origin xyz="0 0 -0.4"/>
  </joint>
  <link name="carriage">
    <inertial>
      <inertia ixx="0.0011" ixy="0" ixz="0" iyy="0.0012" iyz="0" izz="0.0013"/>
      <mass value="0.8"/>
    </inertial>
  </link>
  <joint name="ankle" type="fixed">
    <origin rpy="0 0.3 0" xyz="0 0 -0.45"/>
    <child link="foot"/>
    <parent link="shin"/>
  </joint>
  <link name="shin">
    <inertial>
      <mass value="1.5"/>
      <origin xyz="0 0 -0.25"/>
      <inertia iyy="0.015" ixx="0.015" izz="0.003" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>
  <link name="thigh">
    <inertial>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.005"/>
      <mass value="2.5"/>
      <origin rpy="0.1 0 0" xyz="0 0 -0.2"/>
    </inertial>
  </link>
  <joint type="revolute" name="hip">
    <dynamics friction="0.1" damping="0.2"/>
    <child link="thigh"/>
    <parent link="base"/>
    <axis xyz="0 1 0"/>
    <origin rpy="0 0 0" xyz="0 0.1 0"/>
    <limit effort="80" velocity="5" lower="-1.5" upper="1.5"/>
  </joint>
  <link name="base">
    <inertial>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>
      <origin xyz="0 0 0.05"/>
      <mass value="4"/>
    </inertial>
  </link>
</robot>
)";

std::string hashOf(const std::string& xml, RootJoint root = RootJoint::Fixed) {
  return canonicalHash(loadUrdfString(xml, root));
}

const std::string& baseHash() {
  static const std::string hash = hashOf(kRobot);
  return hash;
}

// `text` with the single occurrence of `from` replaced by `to`.
std::string with(const std::string& text, const std::string& from, const std::string& to) {
  size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "marker '" << from << "' not found";
  if (at == std::string::npos) return text;
  EXPECT_EQ(text.find(from, at + 1), std::string::npos) << "marker '" << from << "' is not unique";
  return text.substr(0, at) + to + text.substr(at + from.size());
}

// Every number token `number` (inside an attribute value) spelled `spelling` instead.
std::string respell(const std::string& text, const std::string& number, const std::string& spelling) {
  auto delimiter = [](char c) { return c == '"' || c == ' '; };
  std::string out;
  size_t from = 0, replaced = 0;
  for (size_t at = text.find(number); at != std::string::npos; at = text.find(number, at + 1)) {
    size_t end = at + number.size();
    if (at == 0 || !delimiter(text[at - 1]) || end >= text.size() || !delimiter(text[end])) continue;
    out += text.substr(from, at - from) + spelling;
    from = end;
    ++replaced;
  }
  EXPECT_GT(replaced, 0u) << "no token " << number;
  return out + text.substr(from);
}

// --- the hash itself -------------------------------------------------------------------

TEST(Canonical, Sha256TestVectors) {
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  EXPECT_EQ(sha256Hex(std::string_view("a\0b", 3)), sha256Hex(std::string("a\0b", 3)));
  EXPECT_NE(sha256Hex(std::string_view("a\0b", 3)), sha256Hex("a"));  // embedded NUL counts
}

TEST(Canonical, HashIsSha256OfTheCanonicalForm) {
  Model m = loadUrdfString(kRobot);
  const std::string hash = canonicalHash(m);
  ASSERT_EQ(hash.size(), 64u);
  for (char c : hash) EXPECT_TRUE(std::isdigit(c) || (c >= 'a' && c <= 'f')) << hash;
  EXPECT_EQ(hash, sha256Hex(canonicalForm(m)));
  // Deterministic: the same text loaded again, or the same model hashed again.
  EXPECT_EQ(canonicalHash(m), hash);
  EXPECT_EQ(canonicalForm(loadUrdfString(kRobot)), canonicalForm(m));
  EXPECT_EQ(baseHash(), hash);
}

TEST(Canonical, FormNamesEveryJointAndFrameButNotTheRobot) {
  Model m = loadUrdfString(kRobot);
  const std::string form = canonicalForm(m);
  for (const std::string& name : m.frameNames())
    EXPECT_NE(form.find("\"" + name + "\""), std::string::npos) << name;
  EXPECT_EQ(form.find("canon\""), std::string::npos) << "the robot's name is not part of the identity";
  EXPECT_EQ(loadUrdfString(with(kRobot, R"(<robot name="canon">)", R"(<robot name="other">)")).name, "other");
  EXPECT_EQ(hashOf(with(kRobot, R"(<robot name="canon">)", R"(<robot name="other">)")), baseHash());
}

// --- the same robot, spelled differently ---------------------------------------------------

TEST(Canonical, SameForReformattedWhitespace) {
  // Everything on one line.
  const std::string one_line = std::regex_replace(kRobot, std::regex(R"(>\s+<)"), "><");
  ASSERT_EQ(one_line.find("\n<"), std::string::npos);
  EXPECT_EQ(hashOf(one_line), baseHash());
  // Attributes on lines of their own, indented with tabs, spaces around '='.
  std::string spread = std::regex_replace(kRobot, std::regex(R"(" )"), "\"\n\t\t");
  spread = std::regex_replace(spread, std::regex(R"( (\w+)=")"), "\n\t$1 = \"");
  EXPECT_EQ(hashOf(spread), baseHash());
  // Several spaces, tabs and line breaks between the numbers of a vector.
  std::string numbers = with(kRobot, R"(<origin xyz="0 0.1 0" rpy="0 0 0"/>)",
                             "<origin xyz=\"  0\t0.1\n        0 \" rpy=\"0  0\r\n0\"/>");
  numbers = with(numbers, R"(<axis xyz="0 0.6 0.8"/>)", "<axis xyz=\"0\t0.6\t0.8\"/>");
  EXPECT_EQ(hashOf(numbers), baseHash());
  // CRLF line ends.
  EXPECT_EQ(hashOf(std::regex_replace(kRobot, std::regex("\n"), "\r\n")), baseHash());
}

TEST(Canonical, SameWithComments) {
  std::string xml =
      with(kRobot, R"(<robot name="canon">)", "<!-- a leg -->\n<robot name=\"canon\">\n<!-- x -->");
  xml = with(xml, R"(<child link="thigh"/>)", "<!-- <child link=\"shin\"/> --><child link=\"thigh\"/>");
  xml = with(xml, R"(<mass value="2.5"/>)", "<mass value=\"2.5\"/><!-- was 2.6 -->");
  xml =
      with(xml, "</robot>", "<!--\n  <joint name=\"ghost\" type=\"revolute\"/>\n-->\n</robot>\n<!-- end -->");
  EXPECT_EQ(hashOf(xml), baseHash());
}

TEST(Canonical, SameWithAttributeOrderSwapped) {
  std::string xml =
      with(kRobot, R"(<joint name="hip" type="revolute">)", R"(<joint type="revolute" name="hip">)");
  xml = with(xml, R"(<origin xyz="0 0.1 0" rpy="0 0 0"/>)", R"(<origin rpy="0 0 0" xyz="0 0.1 0"/>)");
  xml = with(xml, R"(<limit lower="-1.5" upper="1.5" effort="80" velocity="5"/>)",
             R"(<limit velocity="5" effort="80" upper="1.5" lower="-1.5"/>)");
  xml =
      with(xml, R"(<dynamics damping="0.2" friction="0.1"/>)", R"(<dynamics friction="0.1" damping="0.2"/>)");
  xml = with(xml, R"(ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.005")",
             R"(izz="0.005" iyz="0" iyy="0.02" ixz="0" ixy="0" ixx="0.02")");
  EXPECT_EQ(hashOf(xml), baseHash());
}

TEST(Canonical, SameWithElementsReordered) { EXPECT_EQ(hashOf(kReordered), baseHash()); }

TEST(Canonical, SameForOtherSpellingsOfTheSameNumbers) {
  for (const char* spelling : {"1e-1", "0.10000", ".1", "1.0e-1", "+0.1", "100e-3"})
    EXPECT_EQ(hashOf(respell(kRobot, "0.1", spelling)), baseHash()) << spelling;
  EXPECT_EQ(hashOf(respell(respell(kRobot, "2.5", "25e-1"), "4", "4.000")), baseHash());
  EXPECT_EQ(hashOf(respell(respell(kRobot, "1", "1.0"), "-0.2", "-2E-1")), baseHash());
}

TEST(Canonical, SameForNegativeZero) {
  // Every zero of the file (origins, rpy, axes, inertia products, a lower limit) as -0.
  const std::string xml = respell(kRobot, "0", "-0");
  EXPECT_EQ(hashOf(xml), baseHash());
  EXPECT_EQ(hashOf(xml, RootJoint::FreeFlyer), hashOf(kRobot, RootJoint::FreeFlyer));
  const std::string form = canonicalForm(loadUrdfString(xml));
  EXPECT_FALSE(std::regex_search(form, std::regex(R"((^|\s)-0(\s|$))"))) << form;
}

TEST(Canonical, SameWithVisualAndCollisionGeometry) {
  std::string xml = with(kRobot, R"(<link name="thigh">)", R"(<link name="thigh">
    <visual>
      <origin xyz="0 0 -0.2" rpy="0 0 0"/>
      <geometry><cylinder radius="0.05" length="0.4"/></geometry>
      <material name="blue"><color rgba="0 0 1 1"/></material>
    </visual>
    <collision>
      <origin xyz="0 0 -0.2"/>
      <geometry><box size="0.1 0.1 0.4"/></geometry>
    </collision>)");
  xml = with(xml, R"(<link name="foot">)", R"(<link name="foot">
    <collision><geometry><sphere radius="0.04"/></geometry></collision>)");
  xml = with(xml, R"(<robot name="canon">)", R"(<robot name="canon">
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>)");
  EXPECT_EQ(hashOf(xml), baseHash());
}

TEST(Canonical, SameWhenTheWeldedBaseOfAFixedRobotChanges) {
  // With a fixed root the base link never moves: its inertia is not part of the dynamics.
  const std::string heavier = with(kRobot, R"(<mass value="4"/>)", R"(<mass value="40"/>)");
  EXPECT_EQ(hashOf(heavier), baseHash());
  // With a free-flying base it is.
  EXPECT_NE(hashOf(heavier, RootJoint::FreeFlyer), hashOf(kRobot, RootJoint::FreeFlyer));
}

// --- different robots ------------------------------------------------------------------

struct Change {
  const char* what;
  std::string xml;
};

std::vector<Change> changes() {
  const std::string& r = kRobot;
  return {
      {"mass of a moving link", with(r, R"(<mass value="2.5"/>)", R"(<mass value="2.6"/>)")},
      {"mass of a link merged through a fixed joint",
       with(r, R"(<mass value="0.5"/>)", R"(<mass value="0.55"/>)")},
      {"mass at the end of a chain", with(r, R"(<mass value="0.3"/>)", R"(<mass value="0.3000000001"/>)")},
      {"an inertia entry", with(r, R"(izz="0.005")", R"(izz="0.006")")},
      {"an inertia product", with(r, R"(iyy="0.0012" iyz="0")", R"(iyy="0.0012" iyz="0.0001")")},
      {"an inertial origin", with(r, R"(<origin xyz="0 0 -0.25"/>)", R"(<origin xyz="0 0 -0.26"/>)")},
      {"an inertial rpy", with(r, R"(rpy="0.1 0 0")", R"(rpy="0.1 0 0.2")")},
      {"an axis", with(r, R"(<axis xyz="0 1 0"/>)", R"(<axis xyz="1 0 0"/>)")},
      {"an axis reversed", with(r, R"(<axis xyz="0 1 0"/>)", R"(<axis xyz="0 -1 0"/>)")},
      {"an unaligned axis", with(r, R"(<axis xyz="0 0.6 0.8"/>)", R"(<axis xyz="0 0.8 0.6"/>)")},
      {"a joint origin xyz",
       with(r, R"(<origin xyz="0 0.1 0" rpy="0 0 0"/>)", R"(<origin xyz="0 0.1 0.001" rpy="0 0 0"/>)")},
      {"a joint origin rpy",
       with(r, R"(<origin xyz="0 0.1 0" rpy="0 0 0"/>)", R"(<origin xyz="0 0.1 0" rpy="0 0 0.01"/>)")},
      {"a fixed joint origin",
       with(r, R"(<origin xyz="0 0 -0.45" rpy="0 0.3 0"/>)", R"(<origin xyz="0 0 -0.46" rpy="0 0.3 0"/>)")},
      {"a fixed joint rpy", with(r, R"(rpy="0 0.3 0")", R"(rpy="0 0.31 0")")},
      {"a lower limit", with(r, R"(lower="-1.5")", R"(lower="-1.4")")},
      {"an upper limit", with(r, R"(upper="2.5")", R"(upper="2.4")")},
      {"an effort limit", with(r, R"(effort="80")", R"(effort="81")")},
      {"a velocity limit", with(r, R"(velocity="0.7")", R"(velocity="0.75")")},
      {"a prismatic limit", with(r, R"(upper="0.1" effort="200")", R"(upper="0.2" effort="200")")},
      {"damping", with(r, R"(damping="0.2")", R"(damping="0.3")")},
      {"friction", with(r, R"(friction="0.1")", R"(friction="0.15")")},
      {"revolute -> prismatic",
       with(r, R"(<joint name="hip" type="revolute">)", R"(<joint name="hip" type="prismatic">)")},
      {"revolute -> continuous",
       with(r, R"(<joint name="hip" type="revolute">)", R"(<joint name="hip" type="continuous">)")},
      {"revolute -> fixed",
       with(r, R"(<joint name="knee" type="revolute">)", R"(<joint name="knee" type="fixed">)")},
      {"prismatic -> revolute",
       with(r, R"(<joint name="slider" type="prismatic">)", R"(<joint name="slider" type="revolute">)")},
      {"a joint renamed", with(r, R"(<joint name="knee")", R"(<joint name="knee2")")},
      {"a link renamed", with(with(r, R"(<link name="foot">)", R"(<link name="toe">)"),
                              R"(<child link="foot"/>)", R"(<child link="toe"/>)")},
      {"a subtree moved", with(r, R"(<parent link="carriage"/>)", R"(<parent link="base"/>)")},
  };
}

TEST(Canonical, DifferentWhenTheDynamicsOrTheInterfaceChange) {
  std::set<std::string> hashes{baseHash()};
  for (const Change& change : changes()) {
    SCOPED_TRACE(change.what);
    const std::string hash = hashOf(change.xml);
    EXPECT_NE(hash, baseHash());
    EXPECT_TRUE(hashes.insert(hash).second) << "same hash as another change";
  }
}

TEST(Canonical, DifferentForAFreeFlyerRoot) {
  const Model fixed = loadUrdfString(kRobot);
  const Model floating = loadUrdfString(kRobot, RootJoint::FreeFlyer);
  EXPECT_NE(canonicalHash(fixed), canonicalHash(floating));
  EXPECT_NE(canonicalForm(fixed), canonicalForm(floating));
}

TEST(Canonical, DifferentWhenTheModelIsEditedInMemory) {
  const Model base = loadUrdfString(kRobot);
  Model gravity = base;
  gravity.gravity.z() = -9.80665;
  EXPECT_NE(canonicalHash(gravity), canonicalHash(base));
  Model body = base;
  body.bodies[0].lever.x() += 1e-12;
  EXPECT_NE(canonicalHash(body), canonicalHash(base));
  Model frame = base;
  frame.frames.back().placement.translation.y() = 0.5;
  EXPECT_NE(canonicalHash(frame), canonicalHash(base));
  Model renamed = base;
  renamed.name = "another robot";
  EXPECT_EQ(canonicalHash(renamed), canonicalHash(base));
}

}  // namespace
}  // namespace robodiff
