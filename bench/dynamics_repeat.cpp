// Runs one dynamics algorithm N times on one robot and nothing else: the program to
// put under `valgrind --tool=callgrind` for repeatable instruction counts per call
// (bench/callgrind_dynamics.sh subtracts a run with N = 0).
//
//   dynamics_repeat URDF fk|rnea|crba|aba N [--floating-base]
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/urdf_loader.hpp"

int main(int argc, char** argv) {
  using namespace robodiff;
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s URDF fk|rnea|crba|aba N [--floating-base]\n", argv[0]);
    return 2;
  }
  const std::string algorithm = argv[2];
  const long n = std::atol(argv[3]);
  const bool ff = argc > 4 && std::string(argv[4]) == "--floating-base";
  Model model = loadUrdfFile(argv[1], ff ? RootJoint::FreeFlyer : RootJoint::Fixed);
  Data<double> data(model);
  std::mt19937_64 rng(7);
  Eigen::VectorXd q = randomConfiguration(model, rng);
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(model.nv, -1, 1), a = v.reverse(), tau = 0.5 * v;
  double sink = 0;
  for (long i = 0; i < n; ++i) {
    if (algorithm == "fk") forwardKinematics(model, data, q), sink += data.oMi.back().translation[0];
    else if (algorithm == "rnea") sink += rnea(model, data, q, v, a)[0];
    else if (algorithm == "crba") sink += crba(model, data, q)(0, 0);
    else if (algorithm == "aba") sink += aba(model, data, q, v, tau)[0];
    else return std::fprintf(stderr, "unknown algorithm %s\n", algorithm.c_str()), 2;
  }
  std::printf("%g\n", sink);
  return 0;
}
