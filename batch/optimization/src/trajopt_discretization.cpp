// TimeDiscretization: central differences with mirrored ghost knots.
#include "trajopt_discretization.hpp"

namespace robodiff::batch {

TimeDiscretization::TimeDiscretization(int knots, double step) : knots_(knots), step_(step), stencils_(knots) {
  // Ghost knots mirror the trajectory at its ends: q_{-1} = q_1, q_T = q_{T-2}.
  auto mirrored = [&](int j) { return j < 0 ? -j : j > knots - 1 ? 2 * (knots - 1) - j : j; };
  for (int k = 0; k < knots; ++k) {
    std::vector<StencilTerm>& terms = stencils_[k];
    auto add = [&](int j, double q, double v, double a) {
      for (StencilTerm& t : terms)
        if (t.knot == j) {
          t.q += q, t.v += v, t.a += a;
          return;
        }
      terms.push_back({j, q, v, a});
    };
    // v_k = (q_{k+1} - q_{k-1}) / 2h,  a_k = (q_{k+1} - 2 q_k + q_{k-1}) / h^2.
    add(mirrored(k - 1), 0, -1 / (2 * step), 1 / (step * step));
    add(k, 1, 0, -2 / (step * step));
    add(mirrored(k + 1), 0, 1 / (2 * step), 1 / (step * step));
  }
}

}  // namespace robodiff::batch
