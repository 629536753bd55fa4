// Refuses a model whose joint-space mass matrix is singular: a moving joint that moves
// no mass or inertia (e.g. every mass zero, or a revolute joint whose whole subtree is
// massless), for which forward dynamics has no solution.
#pragma once

#include <string>

#include "robodiff/model/model.hpp"

namespace robodiff::detail {

// Throws PhysicallyInvalidModel naming the joint and the links it moves.
void checkMassMatrixRegular(const Model& model, const std::string& source);

}  // namespace robodiff::detail
