// Checks a URDF's XML text before urdfdom sees it, so that every problem is reported
// with the source, the line, the element and the value (urdfdom reports none of these).
#pragma once

#include <array>
#include <map>
#include <string>

namespace robodiff::detail {

// The rpy attributes of the <origin> elements, as written (zero where absent): urdfdom
// keeps only a quaternion made with libm's sin/cos, whose last bits depend on the host,
// so the loader makes the rotations itself from these (portable_geometry.hpp).
struct UrdfRotations {
  std::map<std::string, std::array<double, 3>> joint_rpy;     // by joint name
  std::map<std::string, std::array<double, 3>> inertial_rpy;  // by link name, links with <inertial>
};

// Throws ModelError on the first problem found; `triangle_inequality`: also refuse a
// link whose principal moments violate it. Returns the origins' rpy angles.
UrdfRotations validateUrdfXml(const std::string& xml, const std::string& source, bool triangle_inequality);

}  // namespace robodiff::detail
