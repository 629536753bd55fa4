// Spatial motion vector (twist, spatial acceleration), stored as [linear; angular],
// expressed in some frame at that frame's origin (Featherstone / Pinocchio convention).
#pragma once

#include "robodiff/spatial/force.hpp"
#include "robodiff/spatial/math.hpp"

namespace robodiff {

template <class S> struct Motion {
  Vec3<S> linear = Vec3<S>::Zero();
  Vec3<S> angular = Vec3<S>::Zero();

  static Motion Zero() { return Motion{}; }
  Vec6<S> toVector() const { Vec6<S> v; v << linear, angular; return v; }
  static Motion fromVector(const Vec6<S>& v) { return {v.template head<3>(), v.template tail<3>()}; }

  Motion operator+(const Motion& o) const { return {linear + o.linear, angular + o.angular}; }
  Motion operator-(const Motion& o) const { return {linear - o.linear, angular - o.angular}; }
  Motion& operator+=(const Motion& o) { linear += o.linear; angular += o.angular; return *this; }

  // Motion cross product (this x m): the derivative of m in a frame moving with this.
  Motion cross(const Motion& m) const {
    return {angular.cross(m.linear) + linear.cross(m.angular), angular.cross(m.angular)};
  }
  // Force cross product (this x* f).
  Force<S> cross(const Force<S>& f) const {
    return {angular.cross(f.linear), angular.cross(f.angular) + linear.cross(f.linear)};
  }
  // Power pairing <this, f>.
  S dot(const Force<S>& f) const { return linear.dot(f.linear) + angular.dot(f.angular); }
};

}  // namespace robodiff
