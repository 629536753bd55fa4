// `robodiff trajectory`: a spec's function evaluated at every knot of a trajectory file
// (CSV or JSON) on all cores, its outputs written to a CSV or binary file
// (batch/trajectory: the formats are described in trajectory_table.hpp and
// trajectory_output.hpp). Ctrl-C stops the run and leaves no output file.
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "options/batch_function_options.hpp"
#include "service/service_helpers.hpp"
#include "commands/commands.hpp"
#include "options/function_options.hpp"
#include "output/human_units.hpp"
#include "robodiff/batch/trajectory_error.hpp"
#include "robodiff/batch/trajectory_evaluation.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::cli {
namespace {

namespace fs = std::filesystem;

constexpr int kExitInterrupted = 130;  // as a shell reports a command stopped by SIGINT

struct TrajectoryArgs {
  RobotArgs robot;
  std::string spec, data, out, format;
  BatchFunctionArgs function;
  bool json = false;
};

std::atomic<bool> g_interrupted{false};

extern "C" void onInterrupt(int) { g_interrupted.store(true); }

// SIGINT and SIGTERM set a flag the evaluation polls, for as long as this object lives.
class InterruptFlag {
 public:
  InterruptFlag() {
    g_interrupted = false;
    struct sigaction action {};
    action.sa_handler = onInterrupt;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGINT, &action, &old_int_);
    ::sigaction(SIGTERM, &action, &old_term_);
  }
  ~InterruptFlag() {
    ::sigaction(SIGINT, &old_int_, nullptr);
    ::sigaction(SIGTERM, &old_term_, nullptr);
  }

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

std::string shape(const batch::BlockLayout& block) {
  std::string text = block.name + " " + std::to_string(block.rows);
  if (block.cols != 1) text += " x " + std::to_string(block.cols);
  if (block.sparse) text += " (" + std::to_string(block.size) + " nonzeros)";
  return text;
}

void printSummary(const batch::TrajectoryReport& r, const batch::BatchFunction& f, const FunctionSpec& spec,
                  const Model& model, unsigned threads) {
  std::string outputs;
  for (const batch::BlockLayout& block : f.outputs()) outputs += (outputs.empty() ? "" : ", ") + shape(block);
  std::cout << "trajectory: " << formatGrouped(static_cast<double>(r.knots)) << " knots of " << spec.functionName()
            << " (" << outputs << ") for " << (model.name.empty() ? "the robot" : model.name) << ", "
            << batch::toString(f.backend()) << ", " << threads << " thread" << (threads == 1 ? "" : "s") << "\n";
  std::cout << "  read      " << formatFixed(r.read_seconds, 3) << " s  " << r.data.string() << "\n";
  std::cout << "  evaluate  " << formatFixed(r.evaluate_seconds, 3) << " s  " << formatGrouped(r.knots_per_second)
            << " knots/s\n";
  std::cout << "  write     " << formatFixed(r.write_seconds, 3) << " s  " << r.out.string() << " ("
            << batch::toString(r.format) << ", " << formatBytes(r.bytes) << ")\n";
  if (!r.ignored_columns.empty()) {
    std::cout << "  ignored columns:";
    for (std::size_t i = 0; i < r.ignored_columns.size() && i < 12; ++i) std::cout << " " << r.ignored_columns[i];
    if (r.ignored_columns.size() > 12) std::cout << " ... (" << r.ignored_columns.size() << " in all)";
    std::cout << "\n";
  }
  if (r.non_finite_knots > 0)
    std::cerr << "robodiff: warning: " << r.non_finite_knots << " knot" << (r.non_finite_knots == 1 ? " has" : "s have")
              << " NaN or infinite outputs, the first at " << r.first_non_finite << "\n";
}

nlohmann::json reportJson(const batch::TrajectoryReport& r, const batch::BatchFunction& f, const FunctionSpec& spec,
                          const Model& model, unsigned threads) {
  nlohmann::json outputs = nlohmann::json::array();
  for (const batch::BlockLayout& block : f.outputs())
    outputs.push_back({{"name", block.name}, {"rows", block.rows}, {"cols", block.cols},
                       {"layout", block.sparse ? "csr" : "dense"}, {"size", block.size}});
  return {{"function", spec.functionName()},
          {"model", model.name},
          {"backend", batch::toString(f.backend())},
          {"threads", threads},
          {"data", r.data.string()},
          {"out", r.out.string()},
          {"format", batch::toString(r.format)},
          {"bytes", r.bytes},
          {"knots", r.knots},
          {"outputs", outputs},
          {"read_seconds", r.read_seconds},
          {"evaluate_seconds", r.evaluate_seconds},
          {"write_seconds", r.write_seconds},
          {"knots_per_second", r.knots_per_second},
          {"ignored_columns", r.ignored_columns},
          {"non_finite_knots", r.non_finite_knots},
          {"first_non_finite", r.first_non_finite.empty() ? nlohmann::json() : nlohmann::json(r.first_non_finite)}};
}

void runTrajectory(const TrajectoryArgs& args) {
  // Problems on the command line first, before a possibly long build.
  if (!fs::is_regular_file(args.data)) throw std::runtime_error("--data " + args.data + ": no such file");
  const std::optional<batch::OutputFormat> format =
      args.format.empty() ? std::nullopt : std::optional(batch::parseOutputFormat(args.format));
  if (!format) batch::outputFormatFor(args.out);  // throws naming the path when the extension says nothing
  batch::BatchFunctionOptions options = batchFunctionOptions(args.function);  // checks --backend first

  const std::string urdf_text = readTextFile(args.robot.urdf, "--urdf");
  const Model model =
      loadUrdfString(urdf_text, args.robot.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed, args.robot.urdf);
  const FunctionSpec spec = loadFunctionSpec(args.spec);

  const bool terminal = !args.json && ::isatty(STDERR_FILENO);
  options.on_progress = [&](const std::string& what) {
    if (what == "building" && !args.json)
      std::cerr << "building " << spec.functionName() << " for " << model.name << " into the cache "
                << options.cache_dir.string() << " ...\n";
  };
  const batch::BatchFunction function = batch::BatchFunction::open(model, urdf_text, args.robot.floating_base, spec, options);

  InterruptFlag interrupt;
  batch::TrajectoryJob job;
  job.data = args.data;
  job.out = args.out;
  job.format = format;
  job.threads = args.function.threads;
  job.evaluation.cancelled = [] { return g_interrupted.load(); };
  if (terminal)
    job.evaluation.progress = [](std::uint64_t done, std::uint64_t total) {
      std::cerr << "\revaluating: " << done * 100 / std::max<std::uint64_t>(total, 1) << "% (" << done << " / "
                << total << " knots)" << std::flush;
    };
  batch::TrajectoryReport report;
  try {
    report = batch::runTrajectoryJob(function, model, spec, job);
  } catch (const batch::TrajectoryCancelled& e) {
    if (terminal) std::cerr << "\n";
    std::cerr << "robodiff: interrupted: " << e.what() << "; " << args.out << " was not written\n";
    throw CLI::RuntimeError(kExitInterrupted);
  }
  if (terminal) std::cerr << "\r\033[K" << std::flush;
  const unsigned threads = args.function.threads ? args.function.threads : std::max(1u, std::thread::hardware_concurrency());
  if (args.json)
    std::cout << reportJson(report, function, spec, model, threads).dump() << "\n";
  else
    printSummary(report, function, spec, model, threads);
}

}  // namespace

void addTrajectoryCommand(CLI::App& app) {
  auto args = std::make_shared<TrajectoryArgs>();
  CLI::App* cmd = app.add_subcommand(
      "trajectory", "Evaluate a function (value and derivatives) at every knot of a trajectory file, on all cores");
  addRobotOptions(*cmd, args->robot);
  addSpecOption(*cmd, args->spec, true);
  cmd->add_option("--data", args->data,
                  "The trajectory: CSV with a header row (t, q_<joint>, v_<joint>, a_<joint>, tau_<joint>, or "
                  "<block>_<index>; a user spec's inputs by their names: u_<joint>, target_0, ...), or JSON ({\"t\": "
                  "[...], \"q\": [[...], ...], ...} or [{\"t\": ..., \"q\": [...]}, ...]); columns the function does not "
                  "use are ignored")
      ->required()
      ->type_name("TRAJ.csv|TRAJ.json");
  cmd->add_option("--out", args->out,
                  "Where the outputs go, one row per knot: .csv (t, value_<r>, jacobian_<r>_<c>, ...; a user spec's "
                  "outputs by their names) or .rdb/.bin "
                  "(a JSON header, then float64 little-endian rows); written atomically")
      ->required()
      ->type_name("OUT.csv|OUT.rdb");
  cmd->add_option("--format", args->format, "Output format regardless of --out's extension")
      ->check(CLI::IsMember({"csv", "binary"}))
      ->type_name("csv|binary");
  addBatchFunctionOptions(*cmd, args->function, "knot");
  cmd->add_flag("--json", args->json, "Print the summary as one JSON object");
  cmd->footer(
      "Floating base (--floating-base): q_root_joint_x, _y, _z, _qx, _qy, _qz, _qw and "
      "<block>_root_joint_vx, _vy, _vz, _wx, _wy, _wz. Every used field must be a finite number; a bad row is "
      "reported as FILE:LINE: column NAME: 'TEXT' ....\n"
      "Exit status: 0 done; 1 an error (no output file is written); 130 interrupted (Ctrl-C, SIGTERM; no output "
      "file is written).");
  cmd->callback([args] { runTrajectory(*args); });
}

}  // namespace robodiff::cli
