// Rigid-body spatial inertia: mass, centre of mass (lever) and rotational inertia about
// the centre of mass, all in the body's frame.
#pragma once

#include <type_traits>

#include "robodiff/spatial/force.hpp"
#include "robodiff/spatial/math.hpp"
#include "robodiff/spatial/motion.hpp"
#include "robodiff/spatial/se3.hpp"

namespace robodiff {

// The 10 standard inertial parameters, in Pinocchio's order:
// [m, m*c_x, m*c_y, m*c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz], the rotational inertia
// taken about the body frame's origin (not the centre of mass).
template <class S> using InertialParameters = Eigen::Matrix<S, 10, 1>;

template <class S> struct Inertia {
  S mass = S(0);
  Vec3<S> lever = Vec3<S>::Zero();          // centre of mass in the body frame
  Mat3<S> inertia = Mat3<S>::Zero();        // rotational inertia about the centre of mass

  static Inertia Zero() { return Inertia{}; }

  template <class T> Inertia<T> cast() const {
    return {T(mass), lever.template cast<T>(), inertia.template cast<T>()};
  }

  // Momentum of the body moving with twist v: I * v. In double, about the centre of mass
  // (fewest operations). Traced, the inertia is the model's constants: the first moment
  // h = m c and the inertia about the origin fold into constants, and every product is
  // then one constant times one variable (no m * (c * x) chains): 6% fewer operations
  // in a generated RNEA, more where v is sparse (a joint's motion subspace).
  Force<S> operator*(const Motion<S>& v) const {
    if constexpr (std::is_same_v<S, double>) {
      Vec3<S> lin = mass * (v.linear - lever.cross(v.angular));
      return {lin, inertia * v.angular + lever.cross(lin)};
    } else {
      const Vec3<S> h = mass * lever;
      return {mass * v.linear - h.cross(v.angular), inertiaAboutOrigin() * v.angular + h.cross(v.linear)};
    }
  }

  // I a + v x* (I v): the force that gives the body acceleration a at twist v. Newton's
  // and Euler's equations at the centre of mass, the force then moved to the origin:
  // equal to the two products and the cross product, in fewer operations
  // (docs/code-generation.md, "Each body's force at its centre of mass").
  Force<S> dynamicForce(const Motion<S>& v, const Motion<S>& a) const {
    const Vec3<S>& w = v.angular;
    const Vec3<S> com_velocity = v.linear - lever.cross(w);
    const Vec3<S> com_acceleration = a.linear - lever.cross(a.angular);
    const Vec3<S> f = mass * (com_acceleration + w.cross(com_velocity));
    const Vec3<S> spin = inertia * w;
    return {f, inertia * a.angular + w.cross(spin) + lever.cross(f)};
  }

  // The 6x6 matrix ([linear; angular] ordering).
  Mat6<S> matrix() const {
    Mat6<S> m;
    Mat3<S> cx = skew<S>(lever);
    Mat3<S> mcx = mass * cx;
    m.template block<3, 3>(0, 0) = mass * Mat3<S>::Identity();
    m.template block<3, 3>(0, 3) = -mcx;
    m.template block<3, 3>(3, 0) = mcx;
    // Symmetric to the last bit (each entry once, on and above the diagonal): a traced
    // articulated inertia built on it then stays symmetric node for node.
    const Mat3<S> about_origin = inertia - mcx * cx;
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) m(3 + i, 3 + j) = m(3 + j, 3 + i) = about_origin(i, j);
    return m;
  }

  // This inertia (given in frame b) expressed in frame a, with aMb.
  Inertia transformedBy(const SE3<S>& aMb) const {
    return {mass, aMb.act(lever), aMb.rotation * inertia * aMb.rotation.transpose()};
  }

  // Rotational inertia about the body frame's origin.
  Mat3<S> inertiaAboutOrigin() const {
    Mat3<S> cx = skew<S>(lever);
    return inertia - mass * (cx * cx);
  }

  // Rigid union of two bodies given in the same frame (parallel-axis theorem).
  // Divides by the total mass: the model merges only bodies with positive total mass.
  Inertia operator+(const Inertia& o) const {
    S m = mass + o.mass;
    Vec3<S> c = (mass * lever + o.mass * o.lever) / m;
    Vec3<S> d1 = lever - c, d2 = o.lever - c;
    Mat3<S> s1 = skew<S>(d1), s2 = skew<S>(d2);
    Mat3<S> i = inertia - mass * (s1 * s1) + o.inertia - o.mass * (s2 * s2);
    return {m, c, i};
  }

  InertialParameters<S> parameters() const {
    Mat3<S> io = inertiaAboutOrigin();
    InertialParameters<S> p;
    p << mass, mass * lever.x(), mass * lever.y(), mass * lever.z(),
         io(0, 0), io(0, 1), io(1, 1), io(0, 2), io(1, 2), io(2, 2);
    return p;
  }
};

}  // namespace robodiff
