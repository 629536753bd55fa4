#pragma once
// The lower triangle of a trajectory optimisation's Hessian: knots at most two apart are
// coupled (they share a knot's stencil); within a pair of knots every pair of joints when
// the dynamics enter, or only equal joints (the smoothness term alone). Variables are
// knot-major: knot j's joint i is variable j nv + i.

#include <vector>

#include "robodiff/batch/nonlinear_program.hpp"

namespace robodiff::batch {

class HessianBand {
 public:
  HessianBand(int knots, int nv, bool joints_coupled);

  const SparsityEntries& entries() const { return entries_; }
  // The position in entries() of variable (knot_a, joint_a) with (knot_b, joint_b), for
  // either order; -1 when it is not a structural nonzero.
  int index(int knot_a, int joint_a, int knot_b, int joint_b) const;

 private:
  static constexpr int kReach = 2;  // knots this far apart share a stencil
  int knots_, nv_;
  SparsityEntries entries_;
  std::vector<int> index_;  // [knot][distance 0..kReach][joint][joint of the earlier knot]
};

}  // namespace robodiff::batch
