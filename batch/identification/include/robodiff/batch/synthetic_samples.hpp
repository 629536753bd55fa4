#pragma once
// Synthetic identification data with a known truth, for tests and benchmarks:
//
//   perturbInertias   a copy of a model whose bodies' masses and inertias are changed in a
//                     physically valid way: each composite body scaled by a factor in
//                     [1 - s, 1 + s] (mass and inertia together), plus a random solid box
//                     (mass up to s times the body's, 2-10 cm sides, any orientation, within
//                     5 cm of the centre of mass): a sum of real bodies is a real body;
//   syntheticSamples  states (q, v, a) and tau = RNEA(truth) + Gaussian noise per joint.
//
// Excitation: Fourier (default): each joint follows a finite Fourier series (the usual
// periodic excitation of identification experiments), q_i(t) = q0_i + sum_l alpha_il
// sin(l w t + phi_il) around the middle of its limits, with v and a its exact
// derivatives, sampled at `rate`; Random: every sample drawn independently (q uniform within
// the limits, v in [-1.5, 1.5], a in [-3, 3]). A free-flyer root is drawn at random in
// both cases (RNEA needs no time consistency).

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "robodiff/batch/measured_samples.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

Model perturbInertias(const Model& model, double scale = 0.2, std::uint64_t seed = 1);

enum class Excitation { Fourier, Random };

struct SyntheticOptions {
  std::size_t samples = 1000;
  Excitation excitation = Excitation::Fourier;
  double noise = 0.0;           // torque noise standard deviation, every joint (N m or N)
  Eigen::VectorXd joint_noise;  // per joint (nv) instead, when not empty
  std::uint64_t seed = 1;
  double rate = 100.0;          // samples per second (Fourier; also the t column)
  double period = 10.0;         // the Fourier series' base period, seconds
  int harmonics = 5;
};

MeasuredSamples syntheticSamples(const Model& truth, const SyntheticOptions& options = {});

}  // namespace robodiff::batch
