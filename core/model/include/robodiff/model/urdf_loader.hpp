// Loading a URDF (urdfdom) into a Model.
//
// Joint order is urdfdom's depth-first order (the children of a link sorted by joint
// name), which is also Pinocchio's, so q/v layouts agree one to one. Links joined by
// fixed joints are merged into the moving body they hang from; their frames stay.
#pragma once

#include <stdexcept>
#include <string>

#include "robodiff/model/model.hpp"

namespace robodiff {

// A URDF that cannot be turned into a model. The message names the source (file or
// "<string>"), the line, the element and the offending value.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

Model loadUrdfFile(const std::string& path, RootJoint root = RootJoint::Fixed);
Model loadUrdfString(const std::string& xml, RootJoint root = RootJoint::Fixed,
                     const std::string& source_name = "<string>");

// Rotation entries within this distance of 0 or +-1 are snapped to exactly that value,
// so that origins given as multiples of pi/2 (rpy="1.5707963267948966 0 0") become
// exact permutations and their rounding noise never reaches generated code.
inline constexpr double kRotationSnapTolerance = 1e-14;

}  // namespace robodiff
