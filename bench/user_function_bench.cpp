// Issue 18's targets for user functions on the Panda (../shared), measured in one run:
// the semi-implicit Euler and RK4 steps with their Jacobians against the built-in ABA +
// Jacobian, a 20-knot batch per knot against a call, the tracking cost with gradient and
// Hessian, a whole 20-knot MPC horizon (step, cost, collision cost) in one batch call,
// and the cold build of the step. Generated code is timed as thread CPU time, the median
// of batches, and the median over copies of each library file (where a library's pages
// land moves its speed by up to 2x on this machine). Run by hand, never by ctest:
//   user_function_bench [--copies N] [--quick]
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "commands/bench_timing.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"

#include <unistd.h>

using namespace robodiff;
namespace fs = std::filesystem;
namespace bench = robodiff::cli::bench;

namespace {

struct Built {
  std::string name;
  FunctionSpec spec;
  GeneratedFunctionLibrary lib;
  double build_seconds = 0;
  std::vector<codegen::CompiledFunction> copies;
  std::vector<codegen::LoadedLibrary> libraries;
};

Built build(const Model& model, const std::string& name, const std::string& json, const fs::path& dir, int copies) {
  Built b;
  b.name = name;
  b.spec = parseFunctionSpec(json, name);
  LibraryOptions options;
  options.builder.name = name;
  const auto t0 = std::chrono::steady_clock::now();
  b.lib = generateFunctionLibrary(model, b.spec, dir / name, options);
  b.build_seconds = bench::secondsSince(t0);
  for (int c = 0; c < copies; ++c) {
    const fs::path copy = dir / name / ("copy" + std::to_string(c) + ".so");
    fs::copy_file(b.lib.library, copy, fs::copy_options::overwrite_existing);
    b.libraries.push_back(codegen::LoadedLibrary::open(copy));
    b.copies.push_back(b.libraries.back().function(name));
  }
  return b;
}

// Knot-major inputs of `knots` random states, outputs and work buffers.
struct Buffers {
  std::vector<std::vector<double>> in, out;
  std::vector<const double*> in_ptr;
  std::vector<double*> out_ptr;
  std::vector<double> work;
  Buffers(const Model& model, const Built& b, int knots) {
    const codegen::FunctionDefinition& def = b.lib.built.definition;
    for (const codegen::InputBlock& block : def.inputs) in.emplace_back(static_cast<std::size_t>(knots) * block.size);
    for (const codegen::OutputBlock& block : def.outputs) out.emplace_back(static_cast<std::size_t>(knots) * block.size());
    for (int k = 0; k < knots; ++k) {
      const std::vector<Eigen::VectorXd> x = randomRuntimeInputs(model, b.spec, 1000 + k);
      for (std::size_t i = 0; i < x.size(); ++i) std::copy(x[i].begin(), x[i].end(), in[i].begin() + k * x[i].size());
    }
    for (auto& v : in) in_ptr.push_back(v.data());
    for (auto& v : out) out_ptr.push_back(v.data());
    work.resize(std::max(b.copies.front().workSize(), b.copies.front().batchWorkSize()));
  }
};

double medianOverCopies(const Built& b, const std::function<double(const codegen::CompiledFunction&)>& time) {
  std::vector<double> t;
  for (const codegen::CompiledFunction& f : b.copies) t.push_back(time(f));
  return bench::median(t);
}

// Seconds per single call; seconds per batch call of `knots` knots.
double callSeconds(const Model& model, const Built& b, const bench::TimingPlan& plan) {
  Buffers buf(model, b, 1);
  return medianOverCopies(b, [&](const codegen::CompiledFunction& f) {
    return bench::secondsPerCall([&] { f.evaluate(buf.in_ptr.data(), buf.out_ptr.data(), buf.work.data()); }, plan);
  });
}
double batchSeconds(const Model& model, const Built& b, int knots, const bench::TimingPlan& plan) {
  Buffers buf(model, b, knots);
  return medianOverCopies(b, [&](const codegen::CompiledFunction& f) {
    return bench::secondsPerCall(
        [&] { f.evaluateBatch(knots, buf.in_ptr.data(), buf.out_ptr.data(), buf.work.data()); }, plan);
  });
}

std::string readSpec(const std::string& name) {
  std::ifstream in(fs::path(ROBODIFF_SOURCE_DIR) / "examples" / "specs" / name);
  if (!in) throw std::runtime_error("cannot read examples/specs/" + name);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void row(const char* what, double measured, const char* unit, const std::string& anchor, double target, bool at_most = true) {
  const bool pass = at_most ? measured <= target : measured >= target;
  std::printf("| %-58s | %9.3f %-3s | %-34s | %s %g | %s |\n", what, measured, unit, anchor.c_str(), at_most ? "<=" : ">=",
              target, pass ? "pass" : "MISS");
}

}  // namespace

int main(int argc, char** argv) {
  int copies = 3;
  bench::TimingPlan plan = bench::TimingPlan::full();
  for (int k = 1; k < argc; ++k) {
    if (!std::strcmp(argv[k], "--copies") && k + 1 < argc) copies = std::max(1, std::atoi(argv[++k]));
    else if (!std::strcmp(argv[k], "--quick")) plan = bench::TimingPlan::quick();
  }
  const fs::path urdf = fs::path(ROBODIFF_SHARED_DIR) / "robots" / "panda_arm_fixed_fingers.urdf";
  if (!fs::exists(urdf)) return std::printf("user_function_bench: needs the Panda of ../shared (%s)\n", urdf.c_str()), 0;
  const Model model = loadUrdfFile(urdf.string());
  const fs::path dir = fs::temp_directory_path() / ("robodiff_user_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir);

  const Built aba = build(model, "aba_jacobian",
                          R"({"function": "aba", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "tau"]}]})",
                          dir, copies);
  const Built step = build(model, "euler_step", readSpec("panda_euler_step.json"), dir, copies);
  const Built rk4 = build(model, "rk4_step", readSpec("panda_rk4_step.json"), dir, copies);
  const Built cost = build(model, "tracking_cost", readSpec("panda_tracking_cost.json"), dir, copies);
  const Built knot = build(model, "mpc_knot", readSpec("panda_mpc_knot.json"), dir, copies);

  const double t_aba = callSeconds(model, aba, plan), t_step = callSeconds(model, step, plan);
  const double t_rk4 = callSeconds(model, rk4, plan), t_cost = callSeconds(model, cost, plan);
  const double t_step20 = batchSeconds(model, step, 20, plan) / 20, t_knot = callSeconds(model, knot, plan);
  const double t_horizon = batchSeconds(model, knot, 20, plan);
  std::printf("Panda (nv = %d), gcc -O2 -march=native, %d cop%s of each library, thread CPU time, median of %d batches\n\n",
              model.nv, copies, copies == 1 ? "y" : "ies", plan.batches);
  std::printf("| %-58s | %-13s | %-34s | %-9s | %-6s |\n|---|---:|---|---|---|\n", "measurement", "measured", "same run", "target", "status");
  char anchor[80];
  std::snprintf(anchor, sizeof anchor, "built-in ABA + J %.3f us", t_aba * 1e6);
  row("Euler step + Jacobian [q, v, u], per call / ABA + J", t_step / t_aba, "x", anchor, 1.3);
  row("RK4 step + Jacobian [q, v, u], per call / ABA + J", t_rk4 / t_aba, "x", anchor, 4.5);
  std::snprintf(anchor, sizeof anchor, "one call %.3f us", t_step * 1e6);
  row("Euler step in a 20-knot batch, per knot / one call", t_step20 / t_step, "x", anchor, 0.5);
  row("tracking cost value + gradient + Hessian", t_cost * 1e6, "us", "-", 0.5);
  std::snprintf(anchor, sizeof anchor, "one knot in one call %.3f us", t_knot * 1e6);
  row("20-knot MPC horizon (step, cost, collision) in one batch", t_horizon * 1e6, "us", anchor, 25);
  row("cold build of the Euler step with Jacobians", step.build_seconds, "s", "-", 2.0);
  std::printf("\n| function | operations | with every primitive's trace differentiated | build s |\n|---|---:|---:|---:|\n");
  for (const Built* b : {&aba, &step, &rk4, &cost, &knot})
    std::printf("| %s | %zu | %zu | %.2f |\n", b->name.c_str(), builtOperations(b->lib.built), b->lib.built.traced_operations,
                b->build_seconds);
  fs::remove_all(dir);
  return 0;
}
