// A xacro file (ROS's XML macro language, robot.urdf.xacro) is not a URDF until expanded;
// given to a URDF parser it fails with a puzzling error about links or joints. It is
// recognised here, before any parser, and the error says how to expand it.
#pragma once

#include <string>

namespace robodiff::detail {

// Throws ModelError naming the source and the command that expands it when `xml` uses
// xacro elements (<xacro:...>); an expanded file, which may still declare the xacro
// namespace, passes.
void refuseXacro(const std::string& xml, const std::string& source);

}  // namespace robodiff::detail
