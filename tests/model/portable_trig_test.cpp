// The portable sin/cos behind the model's rotations (core/model/src/portable_trig.hpp):
// within 2 ulp of glibc's std::sin/std::cos (itself within about half an ulp of the
// exact value) over the angles URDFs use, multiples of pi/2 included.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "../../core/model/src/portable_trig.hpp"

namespace robodiff {
namespace {

// |value - reference| in units of the reference's last place.
double portableTrigUlps(double value, double reference) {
  const double r = std::fabs(reference);
  const double ulp = std::nextafter(r, std::numeric_limits<double>::infinity()) - r;
  return std::fabs(value - reference) / ulp;
}

void portableTrigExpectClose(double x) {
  const portable::SinCos sc = portable::sinCos(x);
  EXPECT_LE(portableTrigUlps(sc.sin, std::sin(x)), 2.0) << "sin(" << x << ") = " << sc.sin << " vs " << std::sin(x);
  EXPECT_LE(portableTrigUlps(sc.cos, std::cos(x)), 2.0) << "cos(" << x << ") = " << sc.cos << " vs " << std::cos(x);
}

TEST(PortableTrig, WithinTwoUlpOverMinusTwoPiToTwoPi) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-2 * M_PI, 2 * M_PI);
  for (int i = 0; i < 200000; ++i) portableTrigExpectClose(angle(rng));
}

TEST(PortableTrig, WithinTwoUlpForSmallAndLargeAngles) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> exponent(-30, 6);  // 1e-30 .. 1e6 radians
  for (int i = 0; i < 100000; ++i) {
    const double x = std::pow(10.0, exponent(rng));
    portableTrigExpectClose(i % 2 ? x : -x);
  }
}

// The doubles nearest k*pi/2 leave a reduced argument of about 1e-16: what a reduction
// with a short pi loses first. sin(pi) must come out as 1.2246467991473532e-16.
TEST(PortableTrig, WithinTwoUlpAtMultiplesOfHalfPi) {
  for (int k = -1000; k <= 1000; ++k) {
    portableTrigExpectClose(k * (M_PI / 2));
    portableTrigExpectClose(k * M_PI / 2);
    portableTrigExpectClose(std::nextafter(k * (M_PI / 2), 0.0));
  }
  EXPECT_EQ(portable::sinCos(0.0).sin, 0.0);
  EXPECT_EQ(portable::sinCos(0.0).cos, 1.0);
  EXPECT_LE(portableTrigUlps(portable::sinCos(M_PI).sin, 1.2246467991473532e-16), 1.0);
}

TEST(PortableTrig, HugeAnglesStayCloseAndNonFiniteGiveNaN) {
  for (double x : {1e7, -3.3e9, 1e12}) {  // reduced modulo 2*pi first: error ~ |x| * 4e-17
    const portable::SinCos sc = portable::sinCos(x);
    EXPECT_NEAR(sc.sin, std::sin(x), 1e-16 * std::fabs(x)) << x;
    EXPECT_NEAR(sc.cos, std::cos(x), 1e-16 * std::fabs(x)) << x;
  }
  for (double x : {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN()}) {
    EXPECT_TRUE(std::isnan(portable::sinCos(x).sin)) << x;
    EXPECT_TRUE(std::isnan(portable::sinCos(x).cos)) << x;
  }
}

}  // namespace
}  // namespace robodiff
