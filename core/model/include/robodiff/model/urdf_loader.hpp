// Loading a URDF (urdfdom) into a Model.
//
// Joint order is urdfdom's depth-first order (the children of a link sorted by joint
// name), which is also Pinocchio's, so q/v layouts agree one to one. Links joined by
// fixed joints are merged into the moving body they hang from; their frames stay.
#pragma once

#include <string>

#include "robodiff/model/model.hpp"
#include "robodiff/model/model_error.hpp"
#include "robodiff/model/urdf_limits.hpp"

namespace robodiff {

// What loading checks of the physics, beyond finite numbers, mass >= 0 and inertias
// positive semi-definite (always checked).
enum class PhysicsCheck {
  Kinematic,  // nothing more: URDFs whose inertias are still to be identified load
  Dynamic,    // also the triangle inequality on each link's principal moments, and a mass
              // matrix that is regular (every moving joint moves some mass or inertia):
              // what forward dynamics needs; robodiffd's LoadModel asks for this
};

// Both throw ModelError (model_error.hpp): ModelTooLarge when the text exceeds `limits`
// (checked before any parser sees it), PhysicallyInvalidModel naming the link for a
// negative mass, an inertia that is not positive semi-definite, and with
// PhysicsCheck::Dynamic a triangle inequality violated or a singular mass matrix.
Model loadUrdfFile(const std::string& path, RootJoint root = RootJoint::Fixed, const UrdfLimits& limits = {},
                   PhysicsCheck physics = PhysicsCheck::Kinematic);
Model loadUrdfString(const std::string& xml, RootJoint root = RootJoint::Fixed,
                     const std::string& source_name = "<string>", const UrdfLimits& limits = {},
                     PhysicsCheck physics = PhysicsCheck::Kinematic);

// Rotation entries within this distance of 0 or +-1 are snapped to exactly that value,
// so that origins given as multiples of pi/2 (rpy="1.5707963267948966 0 0") become
// exact permutations and their rounding noise never reaches generated code.
inline constexpr double kRotationSnapTolerance = 1e-14;

}  // namespace robodiff
