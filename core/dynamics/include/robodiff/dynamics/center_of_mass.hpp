// Centre of mass of the whole robot in the world frame, and its total mass. Bodies
// fixed to the universe are not part of the model's dynamics and are not counted.
#pragma once

#include "robodiff/dynamics/data.hpp"
#include "robodiff/dynamics/kinematics.hpp"

namespace robodiff {

template <class S, class Q> const Vec3<S>& centerOfMass(const Model& model, Data<S>& data, const Eigen::MatrixBase<Q>& q) {
  forwardKinematics(model, data, q);
  Vec3<S> weighted = Vec3<S>::Zero();
  S mass = S(0);
  for (int j = 0; j < model.njoints(); ++j) {
    const auto& body = asScalar<S>(model.bodies[j]);
    weighted += body.mass * data.oMi[j].act(body.lever);
    mass += body.mass;
  }
  data.mass = mass;
  data.com = weighted / mass;
  return data.com;
}

}  // namespace robodiff
