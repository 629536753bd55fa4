// HessianBand: the block band of a trajectory optimisation's Hessian, lower triangle.
#include "trajopt_hessian_band.hpp"

#include <utility>

namespace robodiff::batch {

HessianBand::HessianBand(int knots, int nv, bool joints_coupled)
    : knots_(knots), nv_(nv), index_(static_cast<std::size_t>(knots) * (kReach + 1) * nv * nv, -1) {
  for (int k = 0; k < knots; ++k)
    for (int d = 0; d <= kReach && d <= k; ++d)
      for (int i = 0; i < nv; ++i)
        for (int j = 0; j < nv; ++j) {
          if (!joints_coupled && i != j) continue;
          if (d == 0 && j > i) continue;  // the diagonal block's lower triangle
          index_[((static_cast<std::size_t>(k) * (kReach + 1) + d) * nv + i) * nv + j] =
              static_cast<int>(entries_.size());
          entries_.emplace_back(k * nv + i, (k - d) * nv + j);
        }
}

int HessianBand::index(int knot_a, int joint_a, int knot_b, int joint_b) const {
  if (knot_a * nv_ + joint_a < knot_b * nv_ + joint_b) {
    std::swap(knot_a, knot_b);
    std::swap(joint_a, joint_b);
  }
  const int d = knot_a - knot_b;
  if (d > kReach) return -1;
  return index_[((static_cast<std::size_t>(knot_a) * (kReach + 1) + d) * nv_ + joint_a) * nv_ + joint_b];
}

}  // namespace robodiff::batch
