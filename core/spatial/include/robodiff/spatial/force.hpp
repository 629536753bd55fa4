// Spatial force vector (wrench, momentum), stored as [linear (force); angular (moment)],
// expressed in some frame, moments taken about that frame's origin.
#pragma once

#include "robodiff/spatial/math.hpp"

namespace robodiff {

template <class S> struct Force {
  Vec3<S> linear = Vec3<S>::Zero();
  Vec3<S> angular = Vec3<S>::Zero();

  static Force Zero() { return Force{}; }
  Vec6<S> toVector() const { Vec6<S> v; v << linear, angular; return v; }
  static Force fromVector(const Vec6<S>& v) { return {v.template head<3>(), v.template tail<3>()}; }

  Force operator+(const Force& o) const { return {linear + o.linear, angular + o.angular}; }
  Force operator-(const Force& o) const { return {linear - o.linear, angular - o.angular}; }
  Force& operator+=(const Force& o) { linear += o.linear; angular += o.angular; return *this; }
  Force& operator-=(const Force& o) { linear -= o.linear; angular -= o.angular; return *this; }
};

}  // namespace robodiff
