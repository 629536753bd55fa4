// The canonical form of a model and its SHA-256: the identity of a robot for caching.
//
// The form is written from the loaded model, not from the URDF text, so whitespace,
// comments, attribute order, element order and the spelling of numbers ("0.1" vs
// "1e-1") do not change it, while every quantity that changes the dynamics or the
// interface does: joint types, axes, origins, limits, damping, friction, composite
// masses and inertias, frame names and placements, the root joint, gravity. The
// robot's name and visual/collision geometry are left out.
#pragma once

#include <string>
#include <string_view>

#include "robodiff/model/model.hpp"

namespace robodiff {

std::string canonicalForm(const Model& model);
std::string canonicalHash(const Model& model);  // lowercase hex SHA-256 of canonicalForm

std::string sha256Hex(std::string_view bytes);

}  // namespace robodiff
