// An MPC-style step: the dynamics and their Jacobians at the 20 knots of a horizon,
// evaluated as one batch (the library's batched entry point in local mode, one
// EvaluateBatch request otherwise), repeated as a solver would at each iteration.
//
//   mpc_horizon [--urdf FILE] [--knots N] [--iterations N] [--server ADDR] [--cache DIR]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "robodiff/client/client.hpp"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  using Clock = std::chrono::steady_clock;
  std::string urdf = std::string(ROBODIFF_SHARED_DIR) + "/robots/panda_arm_fixed_fingers.urdf";
  if (!fs::exists(urdf)) urdf = std::string(ROBODIFF_SOURCE_DIR) + "/examples/robots/arm7.urdf";
  int knots = 20, iterations = 1000;
  robodiff::client::ClientOptions options;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--urdf") urdf = argv[i + 1];
    else if (a == "--knots") knots = std::atoi(argv[i + 1]);
    else if (a == "--iterations") iterations = std::atoi(argv[i + 1]);
    else if (a == "--server") options.server = robodiff::client::parseServerAddress(argv[i + 1]);
    else if (a == "--cache") options.cache_dir = argv[i + 1];
    else {
      std::fprintf(stderr, "usage: mpc_horizon [--urdf FILE] [--knots N] [--iterations N] [--server ADDR] [--cache DIR]\n");
      return 2;
    }
  }
  try {
    robodiff::client::Client client(options);
    const auto model = client.loadModelFile(urdf);
    const auto f = client.function(
        model, R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}]})");
    const std::size_t in_n = f.inputCount(), out_n = f.outputCount();
    std::vector<double> in(knots * in_n), out(knots * out_n);
    std::vector<double> us;
    for (int it = 0; it < iterations; ++it) {
      // The horizon's states: a straight line in joint space, shifted a little per iteration.
      for (int k = 0; k < knots; ++k)
        for (std::size_t i = 0; i < in_n; ++i) in[k * in_n + i] = 0.01 * (k + 1) * std::sin(0.3 * i + 0.001 * it);
      const auto t = Clock::now();
      const robodiff::Status s = f.evaluateBatch(knots, in, out);
      us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t).count());
      if (!s.ok()) {
        std::fprintf(stderr, "mpc_horizon: %s: %s\n", robodiff::toString(s.code).c_str(), s.message.c_str());
        return 1;
      }
    }
    std::sort(us.begin(), us.end());
    const double p50 = us[us.size() / 2];
    std::printf("mpc_horizon: %s, %d knots per batch via %s, %d iterations\n", urdf.c_str(), knots,
                robodiff::client::toString(f.mode()), iterations);
    std::printf("  batch: p50 %.2f us (%.3f us per knot)  p99 %.2f us  max %.2f us\n", p50, p50 / knots,
                us[us.size() * 99 / 100], us.back());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mpc_horizon: %s\n", e.what());
    return 1;
  }
}
