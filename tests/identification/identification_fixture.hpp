// What the identification tests share: the project's arm7 robot (and the Panda from
// ../shared), a perturbed copy as the known truth, synthetic samples, and the regressor
// on the interpreter (ready at once; the compiled backend is exercised by the CLI test
// and the benchmark).
#pragma once

#include <filesystem>
#include <string>

#include "robodiff/batch/identification.hpp"
#include "robodiff/batch/synthetic_samples.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

struct Robot {
  std::filesystem::path path;
  std::string urdf;
  Model model;
};

inline Robot loadRobot(const std::filesystem::path& path) {
  Robot robot{path, readFile(path), {}};
  robot.model = loadUrdfString(robot.urdf, RootJoint::Fixed, path.string());
  return robot;
}

inline Robot arm7() { return loadRobot(sourceDir() / "examples/robots/arm7.urdf"); }

inline batch::IdentificationOptions interpretedOptions(double holdout = 0.0, bool weighted = false) {
  batch::IdentificationOptions options;
  options.holdout = holdout;
  options.weighted = weighted;
  options.function.backend = batch::Backend::Interpreted;
  options.function.threads = 2;
  return options;
}

inline batch::SyntheticOptions syntheticOptions(std::size_t samples, double noise, std::uint64_t seed = 7) {
  batch::SyntheticOptions options;
  options.samples = samples;
  options.noise = noise;
  options.seed = seed;
  return options;
}

// Poor samples to fit, rich ones to hold out: `poor` samples at 100 Hz of one smooth motion
// (a fraction of a second: the arm hardly leaves its pose), then `rich` samples drawn
// anywhere in the joints' ranges; torque noise `sigma` on both. Least squares on the poor
// part leaves physically invalid bodies (the physical identification tests assert it).
inline batch::MeasuredSamples poorThenRichSamples(const Model& truth, double sigma, std::size_t poor,
                                                  std::size_t rich) {
  const batch::MeasuredSamples first = batch::syntheticSamples(truth, syntheticOptions(poor, sigma, 31));
  batch::SyntheticOptions anywhere = syntheticOptions(rich, sigma, 32);
  anywhere.excitation = batch::Excitation::Random;
  const batch::MeasuredSamples second = batch::syntheticSamples(truth, anywhere);
  const auto join = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    Eigen::MatrixXd m(a.rows(), a.cols() + b.cols());
    m << a, b;
    return m;
  };
  batch::MeasuredSamples out;
  out.source = "<synthetic>";
  out.q = join(first.q, second.q);
  out.v = join(first.v, second.v);
  out.a = join(first.a, second.a);
  out.tau = join(first.tau, second.tau);
  return out;
}

}  // namespace robodiff::testing
