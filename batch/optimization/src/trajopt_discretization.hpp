#pragma once
// The time grid of a trajectory optimisation: T knots h apart, the central-difference
// stencil that gives each knot's (q, v, a) from the positions of at most three knots
// (mirrored ghost knots at both ends: rest, v = 0, there), and the trapezoidal
// quadrature weights of the cost.

#include <vector>

namespace robodiff::batch {

// The coefficients of knot `knot`'s positions in one knot's q, v and a (per joint, the
// same for every joint).
struct StencilTerm {
  int knot = 0;
  double q = 0, v = 0, a = 0;
};

class TimeDiscretization {
 public:
  // knots >= 3, step > 0 (checked by the caller).
  TimeDiscretization(int knots, double step);

  int knots() const { return knots_; }
  double step() const { return step_; }
  // The distinct knots knot k's (q, v, a) depend on, with their coefficients.
  const std::vector<StencilTerm>& stencil(int k) const { return stencils_[k]; }
  // The trapezoidal rule's weight of knot k: h, and h / 2 at both ends.
  double quadratureWeight(int k) const { return k == 0 || k == knots_ - 1 ? step_ / 2 : step_; }

 private:
  int knots_;
  double step_;
  std::vector<std::vector<StencilTerm>> stencils_;
};

}  // namespace robodiff::batch
