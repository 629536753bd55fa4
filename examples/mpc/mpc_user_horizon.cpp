// An MPC horizon on a function the user wrote (examples/specs/panda_mpc_knot.json: the
// Euler step with its Jacobians, the hand's tracking cost with its gradient and Hessian,
// a self-collision barrier with its gradient), evaluated at every knot of a 20-knot
// horizon in ONE evaluateBatch call, repeated as a solver would at each iteration. The
// robot is the Panda from ../shared when there, else the project's arm7 with
// arm7_mpc_knot.json.
//
// The function comes from the cache in local mode (no server needed once it is built:
// `robodiff warmup --urdf URDF --spec SPEC`), else from robodiffd, which builds it.
//
//   mpc_user_horizon [--knots N] [--iterations N] [--server ADDR] [--cache DIR]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "robodiff/client/client.hpp"

namespace {

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Where a named block starts within one knot's doubles, and its size.
struct Slot {
  std::size_t index = 0, offset = 0, size = 0;
};

template <class Blocks, class Size>
Slot slot(const Blocks& blocks, const std::string& name, Size size) {
  std::size_t offset = 0;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    if (blocks[b].name == name) return {b, offset, size(blocks[b])};
    offset += size(blocks[b]);
  }
  throw std::runtime_error("the function has no block '" + name + "'");
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  using Clock = std::chrono::steady_clock;
  std::string urdf = std::string(ROBODIFF_SHARED_DIR) + "/robots/panda_arm_fixed_fingers.urdf";
  std::string spec = std::string(ROBODIFF_SOURCE_DIR) + "/examples/specs/panda_mpc_knot.json";
  if (!fs::exists(urdf)) {
    urdf = std::string(ROBODIFF_SOURCE_DIR) + "/examples/robots/arm7.urdf";
    spec = std::string(ROBODIFF_SOURCE_DIR) + "/examples/specs/arm7_mpc_knot.json";
  }
  int knots = 20, iterations = 200;
  robodiff::client::ClientOptions options;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--knots") knots = std::max(2, std::atoi(argv[i + 1]));
    else if (a == "--iterations") iterations = std::max(1, std::atoi(argv[i + 1]));
    else if (a == "--server") options.server = robodiff::client::parseServerAddress(argv[i + 1]);
    else if (a == "--cache") options.cache_dir = argv[i + 1];
    else {
      std::fprintf(stderr, "usage: mpc_user_horizon [--knots N] [--iterations N] [--server ADDR] [--cache DIR]\n");
      return 2;
    }
  }
  try {
    robodiff::client::Client client(options);
    const auto model = client.loadModelFile(urdf);
    const auto f = client.function(model, readText(spec));
    const auto& layout = f.layout();
    auto in_size = [](const auto& b) { return std::size_t{b.size}; };
    auto out_size = [](const auto& b) { return std::size_t{b.nnz}; };
    const Slot q = slot(layout.inputs, "q", in_size), v = slot(layout.inputs, "v", in_size),
               target = slot(layout.inputs, "target", in_size);
    const Slot q_next = slot(layout.outputs, "q_next", out_size), tracking = slot(layout.outputs, "tracking", out_size),
               collision = slot(layout.outputs, "collision", out_size),
               hessian = slot(layout.outputs, "tracking_hessian", out_size);
    const std::size_t in_n = f.inputCount(), out_n = f.outputCount();
    std::vector<double> in(knots * in_n, 0.0), out(knots * out_n);

    // The solver's current guess: the joints swinging by +-0.25 rad over the horizon with
    // the velocity that does it, no torque (u = 0), the hand's target in front of the robot.
    const double dt = 0.01, T = dt * (knots - 1);
    for (int k = 0; k < knots; ++k) {
      double* x = &in[k * in_n];
      const double s = M_PI * k * dt / T;
      for (std::size_t i = 0; i < q.size; ++i) x[q.offset + i] = 0.125 * (1 - std::cos(s)) * (i % 2 ? -1 : 1);
      for (std::size_t i = 0; i < v.size; ++i) x[v.offset + i] = 0.125 * M_PI / T * std::sin(s) * (i % 2 ? -1 : 1);
      x[target.offset + 0] = 0.4, x[target.offset + 1] = 0.1, x[target.offset + 2] = 0.5;
    }

    std::vector<double> us;
    for (int it = 0; it < iterations; ++it) {
      const auto t = Clock::now();
      const robodiff::Status s = f.evaluateBatch(knots, in, out);
      us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t).count());
      if (!s.ok()) throw robodiff::client::ClientError(s);
    }
    std::sort(us.begin(), us.end());

    // A few numbers a solver would look at: the costs summed over the horizon, the
    // largest dynamics defect |q_next[k] - q[k+1]| of the guess, the Hessian's size.
    double track = 0, collide = 0, defect = 0;
    for (int k = 0; k < knots; ++k) {
      track += out[k * out_n + tracking.offset];
      collide += out[k * out_n + collision.offset];
      if (k + 1 < knots)
        for (std::size_t i = 0; i < q.size; ++i)
          defect = std::max(defect, std::abs(out[k * out_n + q_next.offset + i] - in[(k + 1) * in_n + q.offset + i]));
    }
    const auto H = f.denseBlock(hessian.index, std::span<const double>(out).subspan(0, out_n));
    std::printf("mpc_user_horizon: %s\n  %s, %d knots in one evaluateBatch via %s, %d iterations\n", spec.c_str(),
                urdf.c_str(), knots, robodiff::client::toString(f.mode()), iterations);
    std::printf("  horizon: p50 %.1f us (%.2f us per knot)  p99 %.1f us\n", us[us.size() / 2], us[us.size() / 2] / knots,
                us[us.size() * 99 / 100]);
    std::printf("  tracking cost %.4f  collision barrier %.4f  largest defect %.2e  Hessian %ldx%ld\n", track, collide,
                defect, static_cast<long>(H.rows()), static_cast<long>(H.cols()));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mpc_user_horizon: %s\n  (local mode needs the function in the cache: "
                         "robodiff warmup --urdf %s --spec %s; or start robodiffd)\n",
                 e.what(), urdf.c_str(), spec.c_str());
    return 1;
  }
}
