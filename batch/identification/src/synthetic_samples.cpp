// Synthetic samples from a perturbed model: the known truth for tests and benchmarks.
#include "robodiff/batch/synthetic_samples.hpp"

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "robodiff/batch/identification_error.hpp"
#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/rnea.hpp"

namespace robodiff::batch {

Model perturbInertias(const Model& model, double scale, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), zero_one(0.0, 1.0);
  Model truth = model;
  for (Inertia<double>& body : truth.bodies) {
    if (!(body.mass > 0)) continue;  // a massless body (a free-flyer's placeholder) stays so
    const double f = 1.0 + scale * unit(rng);
    Inertia<double> scaled{f * body.mass, body.lever, f * body.inertia};
    // A solid box: diagonal inertia in its own axes, rotated at random.
    const double mb = scale * body.mass * (0.2 + 0.8 * zero_one(rng));
    const Eigen::Vector3d d(0.02 + 0.08 * zero_one(rng), 0.02 + 0.08 * zero_one(rng), 0.02 + 0.08 * zero_one(rng));
    const Eigen::Vector3d diag(mb / 12 * (d.y() * d.y() + d.z() * d.z()), mb / 12 * (d.x() * d.x() + d.z() * d.z()),
                               mb / 12 * (d.x() * d.x() + d.y() * d.y()));
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized()).toRotationMatrix();
    const Eigen::Vector3d at = body.lever + 0.05 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    body = scaled + Inertia<double>{mb, at, R * diag.asDiagonal() * R.transpose()};
  }
  return truth;
}

MeasuredSamples syntheticSamples(const Model& truth, const SyntheticOptions& options) {
  if (options.joint_noise.size() != 0 && options.joint_noise.size() != truth.nv)
    throw IdentificationError("synthetic samples: " + std::to_string(options.joint_noise.size()) +
                              " noise levels for " + std::to_string(truth.nv) + " joint velocities");
  const std::size_t n = options.samples;
  const auto N = static_cast<Eigen::Index>(n);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);

  MeasuredSamples s;
  s.source = "<synthetic>";
  s.q.resize(truth.nq, N);
  s.v.resize(truth.nv, N);
  s.a.resize(truth.nv, N);
  s.tau.resize(truth.nv, N);
  s.t = Eigen::VectorXd(N);
  for (Eigen::Index k = 0; k < N; ++k) (*s.t)[k] = static_cast<double>(k) / options.rate;

  // Fourier series per 1-dof joint: centre, amplitudes and phases.
  const double w = 2 * M_PI / options.period;
  const int L = std::max(options.harmonics, 1);
  struct Series {
    double centre = 0;
    std::vector<double> amplitude, phase;
  };
  std::vector<Series> series(truth.joints.size());
  for (std::size_t j = 0; j < truth.joints.size(); ++j) {
    const Joint& joint = truth.joints[j];
    if (joint.type == JointType::FreeFlyer) continue;
    double lo = joint.lower[0], hi = joint.upper[0];
    const double span = joint.type == JointType::Revolute ? M_PI : 0.5;
    if (!std::isfinite(lo)) lo = -span;
    if (!std::isfinite(hi)) hi = span;
    Series& f = series[j];
    f.centre = 0.5 * (lo + hi);
    // The amplitudes' sum stays within 40% of the range, so q stays inside the limits.
    double total = 0;
    for (int l = 0; l < L; ++l) {
      f.amplitude.push_back(0.2 + 0.8 * std::abs(unit(rng)));
      f.phase.push_back(M_PI * unit(rng));
      total += f.amplitude.back();
    }
    for (double& a : f.amplitude) a *= 0.4 * (hi - lo) / total;
  }

  Data<double> data(truth);
  for (Eigen::Index k = 0; k < N; ++k) {
    Eigen::VectorXd q = randomConfiguration(truth, rng), v(truth.nv), a(truth.nv);
    for (int i = 0; i < truth.nv; ++i) v[i] = 1.5 * unit(rng), a[i] = 3.0 * unit(rng);
    if (options.excitation == Excitation::Fourier) {
      const double t = (*s.t)[k];
      for (std::size_t j = 0; j < truth.joints.size(); ++j) {
        const Joint& joint = truth.joints[j];
        if (joint.type == JointType::FreeFlyer) continue;
        const Series& f = series[j];
        double qj = f.centre, vj = 0, aj = 0;
        for (int l = 0; l < L; ++l) {
          const double wl = w * (l + 1), arg = wl * t + f.phase[static_cast<std::size_t>(l)];
          const double A = f.amplitude[static_cast<std::size_t>(l)];
          qj += A * std::sin(arg);
          vj += A * wl * std::cos(arg);
          aj -= A * wl * wl * std::sin(arg);
        }
        q[joint.idx_q] = qj;
        v[joint.idx_v] = vj;
        a[joint.idx_v] = aj;
      }
    }
    s.q.col(k) = q;
    s.v.col(k) = v;
    s.a.col(k) = a;
    s.tau.col(k) = rnea(truth, data, q, v, a);
    for (int i = 0; i < truth.nv; ++i) {
      const double sigma = options.joint_noise.size() ? options.joint_noise[i] : options.noise;
      if (sigma > 0) s.tau(i, k) += sigma * gauss(rng);
    }
  }
  return s;
}

}  // namespace robodiff::batch
