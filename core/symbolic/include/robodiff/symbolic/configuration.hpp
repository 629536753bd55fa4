// q0 (+) dq for tracing derivatives in the tangent space: the configuration moved by a
// tangent vector dq (the free-flyer by the SE(3) exponential in the base frame, the
// other joints by plain addition), exact to second order in dq at dq = 0.
//
// Differentiating f(q0 (+) dq) with respect to dq at dq = 0 gives the tangent-space
// derivatives (the golden files' dtau/dq convention for floating bases); first and
// second derivatives at dq = 0 are exact because the truncated terms are O(|dq|^3).
// The truncation keeps the graph free of the exponential's |w| (whose sqrt has no
// derivative at 0) and of branches. Not an integrator for finite steps: use
// robodiff::integrate for those.
#pragma once

#include "robodiff/model/model.hpp"
#include "robodiff/spatial/math.hpp"
#include "robodiff/spatial/se3.hpp"

namespace robodiff::symbolic {

template <class S>
VecX<S> integrateSecondOrder(const Model& model, const VecX<S>& q0, const VecX<S>& dq) {
  VecX<S> q = q0;
  for (const Joint& joint : model.joints) {
    if (joint.type != JointType::FreeFlyer) {
      q[joint.idx_q] = q0[joint.idx_q] + dq[joint.idx_v];
      continue;
    }
    const int iq = joint.idx_q, iv = joint.idx_v;
    const Vec3<S> p0(q0[iq], q0[iq + 1], q0[iq + 2]);
    const Vec3<S> r0(q0[iq + 3], q0[iq + 4], q0[iq + 5]);  // quaternion vector part
    const S w0 = q0[iq + 6];                               // and scalar part (w last)
    const Vec3<S> lin(dq[iv], dq[iv + 1], dq[iv + 2]);
    const Vec3<S> ang(dq[iv + 3], dq[iv + 4], dq[iv + 5]);
    // exp(ang) as a quaternion: (sin(t/2) ang/t, cos(t/2)) = (ang/2, 1 - t^2/8) + O(t^3).
    const Vec3<S> re = S(0.5) * ang;
    const S we = S(1) - S(0.125) * ang.squaredNorm();
    // q0 * exp: the rotation composed in the base frame.
    const Vec3<S> r = w0 * re + we * r0 + r0.cross(re);
    const S w = w0 * we - r0.dot(re);
    // Translation: p0 + R0 V(ang) lin, with V(ang) lin = lin + ang x lin / 2 + O(t^2 |lin|).
    const Mat3<S> R0 = quaternionRotation<S>(r0[0], r0[1], r0[2], w0);
    const Vec3<S> p = p0 + R0 * (lin + S(0.5) * ang.cross(lin));
    for (int k = 0; k < 3; ++k) {
      q[iq + k] = p[k];
      q[iq + 3 + k] = r[k];
    }
    q[iq + 6] = w;
  }
  return q;
}

}  // namespace robodiff::symbolic
