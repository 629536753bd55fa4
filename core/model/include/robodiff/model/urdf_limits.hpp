// Limits on a URDF's text, checked by a non-recursive scan before any XML parser (which
// recurses once per nesting level) sees it, so that no URDF can exhaust the stack or the
// memory of the process that loads it.
//
// The defaults leave ample room for real robots and for the largest robot the generator
// makes (a 10,000-joint chain: 8 MB, ~150,000 elements, ~11,100 links and joints, depth 4):
// - max_bytes 16 MiB: the largest URDF a server accepts by default;
// - max_depth 64: URDFs nest 3 to 6 levels (robot/link/visual/geometry/mesh), Gazebo
//   extensions a few more; 64 levels of parser recursion are a few KB of stack;
// - max_elements 400,000 and max_links = max_joints = 20,000: twice the generator's largest;
//   every traversal of the tree is iterative, so a chain at the limit loads;
// - max_name_length 256: names of links, joints, the robot and other elements and
//   attributes; max_attribute_length 4096 (a file path) for other attribute values.
#pragma once

#include <cstdint>
#include <string>

namespace robodiff {

struct UrdfLimits {
  std::uint64_t max_bytes = std::uint64_t{16} << 20;
  std::uint64_t max_depth = 64;
  std::uint64_t max_elements = 400'000;
  std::uint64_t max_links = 20'000;
  std::uint64_t max_joints = 20'000;
  std::uint64_t max_name_length = 256;
  std::uint64_t max_attribute_length = 4096;
};

// Scans the XML text (tags, comments, CDATA, processing instructions, declarations,
// quoted attribute values) without recursion and throws ModelTooLarge naming the first
// limit exceeded and the value found, e.g. "<string>: the URDF nests elements 100000
// deep; the limit is max_depth = 64". Malformed XML is left to the parser to report.
void checkUrdfLimits(const std::string& xml, const UrdfLimits& limits, const std::string& source);

}  // namespace robodiff
