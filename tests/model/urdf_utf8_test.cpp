// The URDF text must be UTF-8 without NUL bytes (core/model/src/utf8_check.hpp): TinyXML
// reads past the end of a text that ends inside a multi-byte sequence. The first input is
// the fuzzer's (tests/fuzz/regressions/urdf/tinyxml_cut_utf8_sequence.urdf).
#include <gtest/gtest.h>

#include <string>

#include "robodiff/model/model_error.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff {
namespace {

constexpr const char* kPendulum =
    "<robot name=\"p\"><link name=\"base\"/><link name=\"bob\"><inertial><mass value=\"1\"/>"
    "<inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>"
    "<joint name=\"hinge\" type=\"continuous\"><parent link=\"base\"/><child link=\"bob\"/>"
    "<axis xyz=\"0 1 0\"/></joint></robot>";

std::string messageOf(const std::string& urdf) {
  try {
    loadUrdfString(urdf, RootJoint::Fixed, "bad.urdf", {}, PhysicsCheck::Dynamic);
  } catch (const ModelError& e) {
    return e.what();
  }
  return "(loaded)";
}

TEST(UrdfUtf8, SequenceCutAtTheEndIsRefusedBeforeTheParser) {
  const std::string urdf = "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link name=\"a\"/>\xF4\xF4\n";
  EXPECT_EQ(messageOf(urdf), "bad.urdf:3: not valid UTF-8 (byte 0xF4 at offset 57); the URDF must be UTF-8 text");
}

TEST(UrdfUtf8, InvalidBytesAndNulAreNamedWithTheirLine) {
  EXPECT_EQ(messageOf(std::string("<robot name=\"r\">\n\xC0\xAF</robot>")),
            "bad.urdf:2: not valid UTF-8 (byte 0xC0 at offset 17); the URDF must be UTF-8 text");  // overlong '/'
  EXPECT_EQ(messageOf(std::string("<robot name=\"r\">\xED\xA0\x80</robot>")),
            "bad.urdf:1: not valid UTF-8 (byte 0xED at offset 16); the URDF must be UTF-8 text");  // a surrogate
  EXPECT_EQ(messageOf(std::string("<robot name=\"r\">\0</robot>", 26)),
            "bad.urdf:1: a NUL byte (byte 0x00 at offset 16); the URDF must be UTF-8 text");
}

TEST(UrdfUtf8, ValidMultiByteTextStillLoads) {
  std::string urdf = kPendulum;
  urdf.insert(urdf.find("<link"), "<!-- Pendel, \xC3\xA9t\xC3\xA9, \xE2\x82\xAC, \xF0\x9F\xA4\x96 -->");
  const Model model = loadUrdfString("\xEF\xBB\xBF" + urdf, RootJoint::Fixed, "ok.urdf", {}, PhysicsCheck::Dynamic);
  EXPECT_EQ(model.nv, 1);
}

}  // namespace
}  // namespace robodiff
