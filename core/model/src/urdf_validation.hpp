// Checks a URDF's XML text before urdfdom sees it, so that every problem is reported
// with the source, the line, the element and the value (urdfdom reports none of these).
#pragma once

#include <string>

namespace robodiff::detail {

// Throws ModelError on the first problem found; `triangle_inequality`: also refuse a
// link whose principal moments violate it.
void validateUrdfXml(const std::string& xml, const std::string& source, bool triangle_inequality);

}  // namespace robodiff::detail
