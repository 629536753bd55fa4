// sin and cos that give the same bits on every x86-64 host and for every -march.
//
// glibc's libm picks its sin/cos implementation at run time by CPU (with or without
// fused multiply-add), so std::sin can differ in the last bit between two hosts; the
// model's rotations (rpy origins) must not, since they feed the model's identity
// (canonical.hpp). These are plain IEEE double arithmetic in portable_trig.cpp, compiled
// with -ffp-contract=off (core/model/CMakeLists.txt): about 1 ulp from the exact value.
#pragma once

namespace robodiff::portable {

struct SinCos {
  double sin, cos;
};

// sin and cos of x (radians). Non-finite x gives NaN. For |x| up to 1e6 the argument
// is reduced with pi/2 to about 120 bits; beyond, first modulo the double nearest to
// 2*pi, so the error grows as |x| * 2.4e-16 / 2pi (no URDF angle is that large).
SinCos sinCos(double x);

}  // namespace robodiff::portable
