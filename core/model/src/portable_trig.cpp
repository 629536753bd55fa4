// Portable sin/cos (portable_trig.hpp): argument reduction by a three-part pi/2, then
// Taylor polynomials on [-pi/4, pi/4]. Compiled with -ffp-contract=off so that no
// multiply-add is fused: every operation below is one IEEE rounding on every host.
#include "portable_trig.hpp"

#include <cmath>
#include <limits>

namespace robodiff::portable {
namespace {

// pi/2 = kPio2Hi + kPio2Mid + kPio2Lo + 1e-37. kPio2Hi holds 33 significant bits and
// kPio2Mid 32, so k * kPio2Hi and k * kPio2Mid are exact for |k| < 2^20. (Split from pi
// computed with Machin's formula in 400-bit integer arithmetic.)
constexpr double kPio2Hi = 0x1.921fb544p+0;
constexpr double kPio2Mid = 0x1.0b4611a6p-34;
constexpr double kPio2Lo = 0x1.3198a2e037073p-69;
constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;  // 2/pi rounded
constexpr double kTwoPi = 0x1.921fb54442d18p+2;       // 2*pi rounded
constexpr double kReductionLimit = 1e6;               // |k| < 2^20 below it

// x - k*pi/2 = hi + lo (|hi| <= pi/4 + tiny, |lo| <= ulp(hi)), and k mod 4.
struct Reduced {
  double hi, lo;
  int quadrant;
};

// a + b = s + e exactly (Knuth's two-sum; no condition on the magnitudes).
void twoSum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bb = s - a;
  e = (a - (s - bb)) + (b - bb);
}

Reduced reduce(double x) {
  if (std::fabs(x) > kReductionLimit) x = std::fmod(x, kTwoPi);  // fmod is exact
  const double k = std::nearbyint(x * kTwoOverPi);
  const double t = x - k * kPio2Hi;  // exact: k * kPio2Hi is exact and close to x
  double a = 0, a_err = 0;
  twoSum(t, -(k * kPio2Mid), a, a_err);
  Reduced r{};
  twoSum(a, a_err - k * kPio2Lo, r.hi, r.lo);
  r.quadrant = static_cast<int>(static_cast<long long>(k) & 3);
  return r;
}

// Taylor coefficients 1/n! with alternating signs (each division rounds once, at compile
// time). The first omitted terms are below 1.1e-19 (sin) and 3.4e-21 (cos) relative.
constexpr double kS3 = -1.0 / 6.0, kS5 = 1.0 / 120.0, kS7 = -1.0 / 5040.0, kS9 = 1.0 / 362880.0,
                 kS11 = -1.0 / 39916800.0, kS13 = 1.0 / 6227020800.0, kS15 = -1.0 / 1307674368000.0,
                 kS17 = 1.0 / 355687428096000.0;
constexpr double kC4 = 1.0 / 24.0, kC6 = -1.0 / 720.0, kC8 = 1.0 / 40320.0, kC10 = -1.0 / 3628800.0,
                 kC12 = 1.0 / 479001600.0, kC14 = -1.0 / 87178291200.0, kC16 = 1.0 / 20922789888000.0,
                 kC18 = -1.0 / 6402373705728000.0;

// sin(hi + lo) for |hi| <= pi/4: hi + hi^3 (S3 + ...) + lo * cos(hi).
double sinKernel(double hi, double lo) {
  const double z = hi * hi;
  const double p = kS3 + z * (kS5 + z * (kS7 + z * (kS9 + z * (kS11 + z * (kS13 + z * (kS15 + z * kS17))))));
  return hi + ((hi * z) * p + (lo - (0.5 * z) * lo));
}

// cos(hi + lo) for |hi| <= pi/4: 1 - z/2 with its rounding error kept, + z^2 (C4 + ...)
// - lo * sin(hi).
double cosKernel(double hi, double lo) {
  const double z = hi * hi;
  const double q = kC4 + z * (kC6 + z * (kC8 + z * (kC10 + z * (kC12 + z * (kC14 + z * (kC16 + z * kC18))))));
  const double h = 0.5 * z;
  const double w = 1.0 - h;
  const double w_err = (1.0 - w) - h;  // exact: 1 - h == w - w_err
  return w + (w_err + ((z * z) * q - hi * lo));
}

}  // namespace

SinCos sinCos(double x) {
  if (!std::isfinite(x)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan};
  }
  const Reduced r = reduce(x);
  const double s = sinKernel(r.hi, r.lo), c = cosKernel(r.hi, r.lo);
  switch (r.quadrant) {
    case 0: return {s, c};
    case 1: return {c, -s};
    case 2: return {-s, -c};
    default: return {-c, s};
  }
}

}  // namespace robodiff::portable
