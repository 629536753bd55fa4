// The CasADi side, used the way CasADi is used for speed: Pinocchio's algorithm on its
// CasADi scalar (casadi::SX) builds the expression, a casadi::Function (the value, or the
// value and its SX Jacobian) is generated as C by casadi::CodeGenerator
// (casadi_codegen.cpp), compiled by the system gcc -O3 -march=native into a library of its
// own, dlopen'ed and called through the generated C entry point with preallocated
// arg / res / iw / w (sizes from the generated <name>_work).
//
// Each library is built in a child process (child_build.hpp): its wall time is the cold
// build (SX expression + code generation + compile), measured_cc's log there the
// compiler's peak memory; a build over the cap is stopped and reported. Jacobians are in
// the tangent space, as CppADCodeGen's: q enters as integrate(q, dq), called at dq = 0.
// The step rows (step_rows.hpp; CodegenOptions::step_rows: fixed base, nq = nv) are the
// same step and cost on SX; not step_cost_derivatives, whose exact Hessian the check,
// comparing Gauss-Newton Hessians, cannot take.
#include <dlfcn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "anchors.hpp"
#include "casadi_codegen.hpp"
#include "child_build.hpp"
#include "step_rows.hpp"

namespace anchors {
namespace {

namespace fs = std::filesystem;
using robodiff::cli::bench::AlignedDoubles;
using robodiff::cli::bench::doNotOptimize;
using robodiff::cli::bench::secondsPerCall;

// The CasADi rows: the four of `robodiff bench`.
const std::vector<std::string> kCasadiRows = {"rnea_value", "rnea_jacobian_dense", "aba_value", "aba_jacobian"};

bool casadiRowHasJacobian(const std::string& row) {
  return row == "rnea_jacobian_dense" || row == "aba_jacobian" || row == "euler_step_jacobian";
}
// Rows whose last input is tau (not a).
bool casadiRowIsAba(const std::string& row) { return row.rfind("aba", 0) == 0 || isStepRow(row); }

casadi_codegen::Algorithm casadiAlgorithmOf(const std::string& row) {
  using casadi_codegen::Algorithm;
  if (row == "step_cost_value") return Algorithm::step_cost;
  if (isStepRow(row)) return Algorithm::euler_step;
  return row.rfind("aba", 0) == 0 ? Algorithm::aba : Algorithm::rnea;
}

// Rows of the row's output y: nv, or the step's nq + nv (+ 1 with the cost).
Eigen::Index casadiOutputSize(const std::string& row, const pinocchio::Model& m) {
  if (!isStepRow(row)) return m.nv;
  return m.nq + m.nv + (row == "step_cost_value" ? 1 : 0);
}

std::string casadiFunctionName(const std::string& row) { return "anchor_casadi_" + row; }
fs::path casadiLibraryPath(const fs::path& dir, const std::string& row) {
  return dir / (casadiFunctionName(row) + ".so");
}

casadi_codegen::Tree treeOf(const pinocchio::Model& model) {
  casadi_codegen::Tree tree;
  tree.joints.assign(model.joints.begin(), model.joints.end());
  tree.parents.assign(model.parents.begin(), model.parents.end());
  tree.placements.assign(model.jointPlacements.begin(), model.jointPlacements.end());
  tree.inertias.assign(model.inertias.begin(), model.inertias.end());
  tree.armature = model.armature;
  tree.gravity = model.gravity;
  const pinocchio::Frame& frame = model.frames[lastFrame(model)];
  tree.frame_parent = frame.parentJoint;
  tree.frame_placement = frame.placement;
  return tree;
}

// Runs the compiler args[0] with `args` and waits for it; throws, naming `source`, when it fails.
void runCompiler(const std::vector<std::string>& args, const std::string& source) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(args[0] + " failed on " + source);
}

// In the build's child, in its directory: the C source, then the library.
void generateAndCompileCasadi(const std::string& row, const casadi_codegen::Tree& tree) {
  const std::string name = casadiFunctionName(row), source = name + ".c";
  casadi_codegen::StepParameters step;
  step.dt = kStepDt;
  step.control_weight = kControlWeight;
  for (int k = 0; k < 3; ++k) step.target[k] = kCostTarget[static_cast<std::size_t>(k)];
  char error[512] = "";
  if (!casadi_codegen::generateSource(tree, casadiAlgorithmOf(row), step, casadiRowHasJacobian(row), name.c_str(),
                                      source.c_str(), error, sizeof error))
    throw std::runtime_error(error);
  runCompiler({compilerCommand(), "-O3", "-march=native", "-shared", "-fPIC", "-o", name + ".so", source, "-lm"}, source);
}

// The generated C entry points (casadi_int is long long int, casadi_real double).
using CasadiEval = int (*)(const double** arg, double** res, long long* iw, double* w, int mem);
using CasadiWork = int (*)(long long* sz_arg, long long* sz_res, long long* sz_iw, long long* sz_w);

// A loaded library: its entry point, preallocated arg / res / iw / w, inputs and outputs.
struct CasadiLibrary {
  void* handle = nullptr;
  CasadiEval eval = nullptr;
  std::vector<const double*> arg;
  std::vector<double*> res;
  std::vector<long long> iw;
  std::vector<double> w;
  Eigen::VectorXd q, dq, v, u;
  AlignedDoubles y, jacobian;  // on 64-byte boundaries, as robodiff bench's buffers
  Eigen::Index jacobian_rows = 0, jacobian_cols = 0;

  CasadiLibrary(const fs::path& path, const std::string& name) {
    handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) throw std::runtime_error(std::string("dlopen: ") + dlerror());
    eval = reinterpret_cast<CasadiEval>(dlsym(handle, name.c_str()));
    const auto work = reinterpret_cast<CasadiWork>(dlsym(handle, (name + "_work").c_str()));
    if (!eval || !work) throw std::runtime_error("no " + name + " or " + name + "_work in " + path.string());
    long long n_arg = 0, n_res = 0, n_iw = 0, n_w = 0;
    if (work(&n_arg, &n_res, &n_iw, &n_w) != 0) throw std::runtime_error(name + "_work failed");
    arg.assign(static_cast<size_t>(n_arg), nullptr);
    res.assign(static_cast<size_t>(n_res), nullptr);
    iw.assign(static_cast<size_t>(std::max(n_iw, 1LL)), 0);
    w.assign(static_cast<size_t>(std::max(n_w, 1LL)), 0.0);
  }
  ~CasadiLibrary() {
    if (handle) dlclose(handle);
  }
  CasadiLibrary(const CasadiLibrary&) = delete;
  CasadiLibrary& operator=(const CasadiLibrary&) = delete;

  // Points arg / res at the state's inputs and the outputs ((q, v, u) or (q, dq, v, u)).
  void bind(const std::string& row, const pinocchio::Model& m, const State& s) {
    const bool with_jacobian = casadiRowHasJacobian(row);
    q = s.q, dq = Eigen::VectorXd::Zero(m.nv), v = s.v, u = casadiRowIsAba(row) ? s.tau : s.a;
    y.assign(static_cast<size_t>(casadiOutputSize(row, m)), 0.0);
    jacobian_rows = with_jacobian ? static_cast<Eigen::Index>(y.size()) : 0;
    jacobian_cols = with_jacobian ? 3 * m.nv : 0;
    jacobian.assign(static_cast<size_t>(jacobian_rows * jacobian_cols), 0.0);
    std::vector<const double*> inputs = {q.data(), v.data(), u.data()};
    if (with_jacobian) inputs.insert(inputs.begin() + 1, dq.data());
    if (arg.size() < inputs.size() || res.size() < (with_jacobian ? 2u : 1u))
      throw std::runtime_error("the generated " + row + " takes other arguments than expected");
    std::copy(inputs.begin(), inputs.end(), arg.begin());
    res[0] = y.data();
    if (with_jacobian) res[1] = jacobian.data();
  }
  void call() {
    if (eval(arg.data(), res.data(), iw.data(), w.data(), 0) != 0) throw std::runtime_error("CasADi call failed");
    doNotOptimize(y[0]);
    doNotOptimize(jacobian);
  }
  // The outputs as Eigen objects (CasADi writes column-major, as Eigen stores them).
  Output outputs() const {
    return Output{Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size())),
                  Eigen::Map<const Eigen::MatrixXd>(jacobian.data(), jacobian_rows, jacobian_cols), {}, {}, {}};
  }
};

// Builds (or reuses) the library of `row`, then checks and times it.
RowResult runCasadiRow(const std::string& row, const pinocchio::Model& model, const casadi_codegen::Tree& tree,
                       const State& timed, const std::vector<State>& checks, const Timing& plan,
                       const CodegenOptions& options) {
  RowResult r;
  r.name = row;
  const fs::path dir = fs::path(options.workdir) / row, library = casadiLibraryPath(dir, row);
  if (!(options.reuse && reuseBuild(dir, library, r))) {
    std::fprintf(stderr, "anchors_bench: CasADi building %s ...\n", row.c_str());
    buildInChild(dir, library, options.cap_seconds, [&] { generateAndCompileCasadi(row, tree); }, r);
  }
  if (r.status != "ok" || options.build_only) return r;
  CasadiLibrary lib(library, casadiFunctionName(row));
  for (const State& s : checks) {
    lib.bind(row, model, s);
    lib.call();
    r.outputs.push_back(lib.outputs());
  }
  lib.bind(row, model, timed);
  r.us = 1e6 * secondsPerCall([&] { lib.call(); }, plan);
  return r;
}

}  // namespace

std::vector<std::string> casadiRowNames(bool step_rows) {
  std::vector<std::string> names = kCasadiRows;
  if (step_rows) names.insert(names.end(), kGeneratedStepRows.begin(), kGeneratedStepRows.end());
  return names;
}

std::string casadiVersion() {
  char version[64] = "";
  casadi_codegen::casadiVersion(version, sizeof version);
  return version;
}

std::vector<RowResult> runCasadi(const pinocchio::Model& model, const State& timed, const std::vector<State>& checks,
                                 const Timing& plan, const CodegenOptions& options) {
  const casadi_codegen::Tree tree = treeOf(model);
  std::vector<RowResult> rows;
  for (const std::string& row : casadiRowNames(options.step_rows)) {
    if (!options.only.empty() && std::find(options.only.begin(), options.only.end(), row) == options.only.end()) {
      RowResult skipped;
      skipped.name = row, skipped.status = "skipped";
      rows.push_back(std::move(skipped));
      continue;
    }
    try {
      rows.push_back(runCasadiRow(row, model, tree, timed, checks, plan, options));
    } catch (const std::exception& e) {
      RowResult failed;
      failed.name = row, failed.status = "failed", failed.note = e.what();
      rows.push_back(std::move(failed));
    }
  }
  return rows;
}

}  // namespace anchors
