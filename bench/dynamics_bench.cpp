// Double-precision FK, RNEA, CRBA and ABA for every robot in ../shared/robots and the
// project's own example robots, then a table in microseconds per call with the ratio
// to Pinocchio's figures measured on this machine kind (../shared/notes/anchors.md;
// Pinocchio is not packaged for Debian, so it cannot run in the same process).
//
//   dynamics_bench [google-benchmark flags, e.g. --benchmark_min_time=0.5]
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace {

using namespace robodiff;

struct Robot {
  std::string name;
  Model model;
};

struct Anchor {
  double rnea = 0, crba = 0, aba = 0;  // Pinocchio 3.7, µs per call; 0: not measured
};

const std::map<std::string, Anchor> kPinocchio = {
    {"panda", {0.80, 0.39, 1.6}},
    {"ur5", {0.69, 0, 0}},
    {"talos", {3.9, 1.9, 7.6}},
};

std::vector<Robot> robots() {
  std::vector<Robot> out;
  std::filesystem::path shared = ROBODIFF_SHARED_DIR;
  if (const char* env = std::getenv("ROBODIFF_SHARED")) shared = env;
  const std::pair<const char*, const char*> external[] = {
      {"panda", "panda_arm_fixed_fingers.urdf"}, {"ur5", "ur5_robot.urdf"}, {"talos", "talos_reduced.urdf"}};
  for (auto [name, file] : external) {
    std::filesystem::path p = shared / "robots" / file;
    if (std::filesystem::exists(p)) out.push_back({name, loadUrdfFile(p.string())});
    else std::fprintf(stderr, "note: %s not found, skipping %s\n", p.c_str(), name);
  }
  std::filesystem::path own = std::filesystem::path(ROBODIFF_SOURCE_DIR) / "examples" / "robots";
  for (const char* name : {"arm7", "quadruped", "humanoid"}) {
    std::filesystem::path p = own / (std::string(name) + ".urdf");
    if (std::filesystem::exists(p)) out.push_back({name, loadUrdfFile(p.string())});
  }
  return out;
}

struct State {
  Eigen::VectorXd q, v, a, tau;
};

State randomState(const Model& model) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  State s{randomConfiguration(model, rng), Eigen::VectorXd(model.nv), Eigen::VectorXd(model.nv),
          Eigen::VectorXd(model.nv)};
  for (int i = 0; i < model.nv; ++i) s.v[i] = u(rng), s.a[i] = u(rng), s.tau[i] = u(rng);
  return s;
}

// Collects the per-call time of each benchmark while printing the usual console output.
class Collect : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, double> micros;
  std::set<std::string> medians;
  void ReportRuns(const std::vector<Run>& runs) override {
    // With --benchmark_repetitions the median is kept, else the single run.
    for (const Run& r : runs) {
      const std::string name = r.run_name.str();
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name == "median") {
        micros[name] = r.GetAdjustedRealTime() / 1e3;
        medians.insert(name);
      } else if (r.run_type == Run::RT_Iteration && !medians.count(name)) {
        micros[name] = r.GetAdjustedRealTime() / 1e3;
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  static std::vector<Robot> all = robots();
  const char* algorithms[] = {"FK", "RNEA", "CRBA", "ABA"};
  for (const Robot& robot : all) {
    const Model* m = &robot.model;
    auto state = std::make_shared<State>(randomState(*m));
    auto data = std::make_shared<Data<double>>(*m);
    benchmark::RegisterBenchmark((robot.name + "/FK").c_str(), [=](benchmark::State& st) {
      for (auto _ : st) {
        forwardKinematics(*m, *data, state->q);
        benchmark::DoNotOptimize(data->oMi.back());
      }
    })->Unit(benchmark::kNanosecond);
    benchmark::RegisterBenchmark((robot.name + "/RNEA").c_str(), [=](benchmark::State& st) {
      for (auto _ : st) benchmark::DoNotOptimize(rnea(*m, *data, state->q, state->v, state->a).data());
    })->Unit(benchmark::kNanosecond);
    benchmark::RegisterBenchmark((robot.name + "/CRBA").c_str(), [=](benchmark::State& st) {
      for (auto _ : st) benchmark::DoNotOptimize(crba(*m, *data, state->q).data());
    })->Unit(benchmark::kNanosecond);
    benchmark::RegisterBenchmark((robot.name + "/ABA").c_str(), [=](benchmark::State& st) {
      for (auto _ : st) benchmark::DoNotOptimize(aba(*m, *data, state->q, state->v, state->tau).data());
    })->Unit(benchmark::kNanosecond);
  }
  Collect reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);

  std::printf("\nrobodiff double dynamics, µs per call (ratio = robodiff / Pinocchio 3.7 on this machine kind;"
              " target <= 1.5)\n\n");
  std::printf("| robot | nv | FK | RNEA | CRBA | ABA | RNEA ratio | CRBA ratio | ABA ratio |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (const Robot& robot : all) {
    auto t = [&](const char* alg) { return reporter.micros[robot.name + "/" + alg]; };
    auto ratio = [](double ours, double anchor) {
      char buf[16];
      std::snprintf(buf, sizeof buf, "%.2f", ours / anchor);
      return anchor > 0 ? std::string(buf) : std::string("-");
    };
    Anchor anchor = kPinocchio.count(robot.name) ? kPinocchio.at(robot.name) : Anchor{};
    std::printf("| %s | %d | %.3f | %.3f | %.3f | %.3f | %s | %s | %s |\n", robot.name.c_str(), robot.model.nv,
                t(algorithms[0]), t(algorithms[1]), t(algorithms[2]), t(algorithms[3]),
                ratio(t("RNEA"), anchor.rnea).c_str(), ratio(t("CRBA"), anchor.crba).c_str(),
                ratio(t("ABA"), anchor.aba).c_str());
  }
  benchmark::Shutdown();
  return 0;
}
