#include "xacro_check.hpp"

#include "robodiff/model/model_error.hpp"

namespace robodiff::detail {
namespace {

// Whether `xml` has a <xacro:...> element outside comments (expanded files keep
// commented-out macro calls).
bool hasXacroElement(const std::string& xml) {
  for (std::size_t at = 0; (at = xml.find('<', at)) != std::string::npos;) {
    if (xml.compare(at, 4, "<!--") == 0) {
      const std::size_t end = xml.find("-->", at + 4);
      if (end == std::string::npos) return false;
      at = end + 3;
      continue;
    }
    if (xml.compare(at, 7, "<xacro:") == 0) return true;
    ++at;
  }
  return false;
}

}  // namespace

void refuseXacro(const std::string& xml, const std::string& source) {
  // An expanded file keeps the xmlns:xacro declaration: only a xacro element counts.
  if (!hasXacroElement(xml)) return;
  const std::string file = source.empty() ? "robot.urdf.xacro" : source;
  throw ModelError(source + ": this is a xacro file (it uses <xacro:...> macros), not a URDF; expand it first: "
                   "`xacro " + file + " > robot.urdf` (ROS 2: `ros2 run xacro xacro " + file +
                   " -o robot.urdf`), then give robot.urdf");
}

}  // namespace robodiff::detail
