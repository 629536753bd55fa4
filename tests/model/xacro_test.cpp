// A xacro file given where a URDF is expected: refused before any parser, naming the
// file and the command that expands it (it used to fail with "the robot has no <link>").
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "robodiff/model/urdf_loader.hpp"
#include "support/temp_dir.hpp"

namespace robodiff {
namespace {

const std::string kXacro = R"(<?xml version="1.0"?>
<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="length" value="0.3"/>
  <xacro:macro name="segment" params="name">
    <link name="${name}"/>
  </xacro:macro>
  <xacro:segment name="base"/>
</robot>
)";

std::string xacroErrorOf(const std::string& path) {
  try {
    loadUrdfFile(path);
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

TEST(Xacro, AXacroFileIsRefusedWithTheCommandThatExpandsIt) {
  testing::TempDir tmp;
  const auto path = tmp.file("arm.urdf.xacro", kXacro);
  const std::string message = xacroErrorOf(path.string());
  EXPECT_EQ(message.rfind(path.string() + ": this is a xacro file", 0), 0u) << message;
  EXPECT_NE(message.find("xacro " + path.string() + " > robot.urdf"), std::string::npos) << message;
  EXPECT_NE(message.find("ros2 run xacro xacro"), std::string::npos) << message;
}

TEST(Xacro, AnExpandedFileThatStillDeclaresTheNamespaceLoads) {
  testing::TempDir tmp;  // xacro's output keeps xmlns:xacro on <robot>
  const auto path = tmp.file(
      "one.urdf", R"(<robot name="one" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="base"/>
<!-- <xacro:transmission name="${name}"/> left commented out -->
</robot>)");
  EXPECT_NO_THROW(loadUrdfFile(path.string()));
}

}  // namespace
}  // namespace robodiff
