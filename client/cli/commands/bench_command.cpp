// `robodiff bench`: the benchmark table of one robot, reproducible from the command
// line. Builds (cold, into a temporary directory) RNEA value, RNEA value + Jacobian in
// [q, v, a] (dense and sparse), ABA value and ABA value + Jacobian in [q, v, tau], then
// times per call: double RNEA and ABA (core/dynamics), each generated function, the
// interpreter on both Jacobians, central finite differences of double RNEA, and batches
// of 1,000 knots on one thread and on every hardware thread. Ratios come from the same
// run; for the robots of ../shared/notes/anchors.md (Panda, UR5, Talos with a fixed
// base) the figures of Pinocchio and CppADCodeGen on this machine kind are shown, and
// the issue's targets get PASS or MISS.
#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <thread>

#include "output/bench_report.hpp"
#include "commands/bench_timing.hpp"
#include "commands/commands.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/dynamics/all.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_library.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::cli {
namespace {

namespace fs = std::filesystem;
using namespace bench;

constexpr std::uint64_t kKnots = 1000;
constexpr std::uint64_t kSeed = 1;
constexpr double kFiniteDifferenceStep = 1e-6;

struct Options {
  std::string urdf, keep;
  bool floating_base = false, json = false, markdown = false, quick = false;
  int copies = 3;
};

// --- where the libraries are built --------------------------------------------------

class WorkDir {
 public:
  explicit WorkDir(const std::string& keep) {
    if (!keep.empty()) {
      path_ = keep;
      fs::create_directories(path_);
      return;
    }
    std::string pattern = (fs::temp_directory_path() / "robodiff-bench-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot create a temporary directory " + pattern);
    path_ = pattern;
    remove_ = true;
  }
  ~WorkDir() {
    std::error_code ec;
    if (remove_) fs::remove_all(path_, ec);
  }
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  bool remove_ = false;
};

// --- figures of other projects and the issue's targets ----------------------------

struct Anchors {
  std::map<std::string, std::string> text;  // row name -> figures of other projects
  std::map<std::string, Target> targets;    // row name -> target on the value
};

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

Target atMost(double limit, const std::string& unit) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "<= %g %s", limit, unit.c_str());
  return {limit, "", buf};
}

// ../shared/notes/anchors.md: Pinocchio 3.7, CppAD(CodeGen) on a 2-core Rocket Lake.
std::optional<Anchors> anchorsFor(const Model& model) {
  if (model.root != RootJoint::Fixed) return std::nullopt;
  const std::string name = lower(model.name);
  Anchors a;
  if (name.find("panda") != std::string::npos && model.nv == 7) {
    a.text = {{"rnea_double", "Pinocchio RNEA 0.80"},
              {"aba_double", "Pinocchio ABA 1.57-1.66"},
              {"rnea_value", "CppADCodeGen 0.163"},
              {"rnea_jacobian_dense", "CppADCodeGen 1.79; Pinocchio derivatives 2.90; CppAD tape 31.3"},
              {"aba_value", "CppADCodeGen 0.42"},
              {"aba_jacobian", "Pinocchio derivatives 4.32; CppADCodeGen 8.96"},
              {"rnea_fd", "central FD 36.7"},
              {"build.rnea_jacobian_dense.total", "CppADCodeGen 2.3 s -O3 compile, 116 MB, 155 KB C"},
              {"build.aba_jacobian.total", "CppADCodeGen 33.5 s -O3 compile, 715 MB, 647 KB C"}};
    a.targets = {{"rnea_value", atMost(0.163, "µs")},
                 {"rnea_jacobian_dense", atMost(0.9, "µs")},
                 {"aba_jacobian", atMost(2.2, "µs")},
                 {"build.rnea_jacobian_dense.total", atMost(1, "s")},
                 {"build.aba_jacobian.total", atMost(3, "s")}};
    return a;
  }
  if (name.find("talos") != std::string::npos && model.nv == 32) {
    a.text = {{"rnea_double", "Pinocchio RNEA 3.89"},
              {"aba_double", "Pinocchio ABA 7.5-7.9"},
              {"rnea_value", "CppADCodeGen 0.666"},
              {"rnea_jacobian_dense", "CppADCodeGen 9.32; Pinocchio derivatives 15.0; CppAD tape 520"},
              {"aba_jacobian", "Pinocchio derivatives 22.6; CppADCodeGen 391-497"},
              {"rnea_fd", "central FD 750"},
              {"build.rnea_jacobian_dense.total", "CppADCodeGen 29 s -O3 compile, 538 MB, 735 KB C"},
              {"build.aba_jacobian.total", "CppADCodeGen 96 s -O3 compile, 1.9 GB, 6.6 MB C"}};
    a.targets = {{"rnea_jacobian_dense", atMost(4.7, "µs")},
                 {"aba_jacobian", atMost(11, "µs")},
                 {"build.rnea_jacobian_dense.total", atMost(10, "s")},
                 {"build.aba_jacobian.total", atMost(30, "s")}};
    return a;
  }
  if (name.find("ur5") != std::string::npos && model.nv == 6) {
    a.text = {{"rnea_double", "Pinocchio RNEA 0.69"},
              {"rnea_jacobian_dense", "Pinocchio derivatives 2.50-2.58; CppAD tape 14.8"},
              {"rnea_fd", "central FD 27.1"}};
    return a;
  }
  return std::nullopt;
}

// --- the machine -------------------------------------------------------------------

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos) {
        std::size_t b = line.find_first_not_of(" \t", colon + 1);
        return b == std::string::npos ? "" : line.substr(b);
      }
    }
  return "unknown CPU";
}

unsigned hardwareThreads() { return std::max(1u, std::thread::hardware_concurrency()); }

std::uint64_t processPeakBytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<std::uint64_t>(u.ru_maxrss) * 1024;  // Linux: KiB
}

std::string today() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d", std::gmtime(&t));
  return buf;
}

// --- the functions -----------------------------------------------------------------

struct Generated {
  std::string name, label;
  FunctionSpec spec;
  GeneratedFunctionLibrary lib;
  double total_seconds = 0;
  std::uint64_t process_peak_bytes = 0;
  // The library loaded from `copies` files (the built one first): identical bytes on
  // other pages, because where a library's pages land moves its speed by up to 2x.
  std::vector<codegen::CompiledFunction> copies;
  const codegen::CompiledFunction& fn() const { return copies.front(); }
};

// Median of `copies` timings, one per copy of the library (`time` returns seconds).
template <class Time> double medianOverCopies(const Generated& g, Time&& time) {
  std::vector<double> t;
  for (const codegen::CompiledFunction& f : g.copies) t.push_back(time(f));
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

struct SpecText {
  const char* name;
  const char* label;
  const char* json;
};

const SpecText kSpecs[] = {
    {"rnea_value", "RNEA value", R"({"function": "rnea", "outputs": [{"kind": "value"}]})"},
    {"rnea_jacobian_dense", "RNEA + Jacobian [q,v,a], dense",
     R"({"function": "rnea", "outputs": [{"kind": "value"},
        {"kind": "jacobian", "wrt": ["q", "v", "a"], "layout": "dense"}]})"},
    {"rnea_jacobian_sparse", "RNEA + Jacobian [q,v,a], sparse",
     R"({"function": "rnea", "outputs": [{"kind": "value"},
        {"kind": "jacobian", "wrt": ["q", "v", "a"], "layout": "sparse"}]})"},
    {"aba_value", "ABA value", R"({"function": "aba", "outputs": [{"kind": "value"}]})"},
    {"aba_jacobian", "ABA + Jacobian [q,v,tau]",
     R"({"function": "aba", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "tau"]}]})"},
};

std::string withBuild(const char* json) {
  // Every spec: all inputs variable (the default), O2 and -march=native.
  std::string s = json;
  s.insert(s.size() - 1, R"(, "build": {"optimization": "O2", "march_native": true})");
  return s;
}

// Input and output buffers of `knots` knots (knot-major per block, abi.h) and a work buffer.
struct Buffers {
  std::vector<std::vector<double>> in, out;
  std::vector<std::uint32_t> in_size, out_size;
  std::vector<const double*> in_ptr;
  std::vector<double*> out_ptr;
  std::vector<double> work;

  Buffers(const Model& model, const Generated& g, std::uint64_t knots, std::size_t work_size) : work(work_size) {
    const codegen::FunctionDefinition& def = g.lib.built.definition;
    for (const codegen::InputBlock& b : def.inputs) in.emplace_back(knots * b.size), in_size.push_back(b.size);
    for (const codegen::OutputBlock& b : def.outputs) out.emplace_back(knots * b.size()), out_size.push_back(b.size());
    for (std::uint64_t k = 0; k < knots; ++k) {
      const std::vector<Eigen::VectorXd> x = randomRuntimeInputs(model, g.spec, kSeed + k);
      if (x.size() != in.size()) throw std::logic_error("bench: input blocks of " + g.name + " differ from the spec");
      for (std::size_t b = 0; b < x.size(); ++b)
        std::copy(x[b].data(), x[b].data() + x[b].size(), &in[b][k * in_size[b]]);
    }
    for (auto& v : in) in_ptr.push_back(v.data());
    for (auto& v : out) out_ptr.push_back(v.data());
  }
  Eigen::VectorXd input(std::size_t block, std::uint64_t knot = 0) const {
    return Eigen::Map<const Eigen::VectorXd>(&in[block][knot * in_size[block]], in_size[block]);
  }
  Eigen::VectorXd output(std::size_t block, std::uint64_t knot = 0) const {
    return Eigen::Map<const Eigen::VectorXd>(&out[block][knot * out_size[block]], out_size[block]);
  }
};

// Central differences of double RNEA over [q, v, a]: 2 * 3nv RNEA calls and the
// differencing, into J (nv x 3nv, q columns in the tangent space).
class RneaFiniteDifferences {
 public:
  RneaFiniteDifferences(const Model& model, Eigen::VectorXd q, Eigen::VectorXd v, Eigen::VectorXd a)
      : model_(model),
        data_(model),
        q_(std::move(q)),
        v_(std::move(v)),
        a_(std::move(a)),
        plus_(model.nv),
        dq_(Eigen::VectorXd::Zero(model.nv)),
        J_(model.nv, 3 * model.nv) {}

  void operator()() {
    const int nv = model_.nv;
    const double h = kFiniteDifferenceStep, s = 0.5 / h;
    for (int j = 0; j < nv; ++j) {
      if (model_.root == RootJoint::Fixed) {  // every joint 1-dof with idx_q = idx_v: q[j] +- h
        column(q_, j, j);
      } else {
        dq_[j] = h;
        plus_ = rnea(model_, data_, integrate(model_, q_, dq_), v_, a_);
        dq_[j] = -h;
        const auto& minus = rnea(model_, data_, integrate(model_, q_, dq_), v_, a_);
        J_.col(j) = (plus_ - minus) * s;
        dq_[j] = 0;
      }
    }
    for (int j = 0; j < nv; ++j) column(v_, j, nv + j);
    for (int j = 0; j < nv; ++j) column(a_, j, 2 * nv + j);
  }
  const Eigen::MatrixXd& jacobian() const { return J_; }

 private:
  void column(Eigen::VectorXd& x, int i, int col) {
    const double x0 = x[i], h = kFiniteDifferenceStep;
    x[i] = x0 + h;
    plus_ = rnea(model_, data_, q_, v_, a_);
    x[i] = x0 - h;
    const auto& minus = rnea(model_, data_, q_, v_, a_);
    J_.col(col) = (plus_ - minus) * (0.5 / h);
    x[i] = x0;
  }

  const Model& model_;
  Data<double> data_;
  Eigen::VectorXd q_, v_, a_, plus_, dq_;
  Eigen::MatrixXd J_;
};

double maxAbs(const Eigen::MatrixXd& m) { return m.size() ? m.cwiseAbs().maxCoeff() : 0.0; }
double relativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected) {
  return maxAbs(actual - expected) / std::max(1.0, maxAbs(expected));
}

Row makeRow(std::string name, std::string label, std::string short_label, Unit unit, double value,
            std::vector<Ratio> ratios = {}) {
  Row r;
  r.name = std::move(name);
  r.label = std::move(label);
  r.short_label = std::move(short_label);
  r.unit = unit;
  r.value = value;
  r.ratios = std::move(ratios);
  return r;
}

// --- the run -----------------------------------------------------------------------

void run(const Options& o) {
  const Model model = loadUrdfFile(o.urdf, o.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed);
  const std::optional<Anchors> anchors = anchorsFor(model);
  const TimingPlan plan = o.quick ? TimingPlan::quick() : TimingPlan::full();
  const unsigned threads = hardwareThreads();
  WorkDir dir(o.keep);
  auto progress = [](const std::string& s) { std::cerr << "bench: " << s << std::endl; };

  Report report;
  report.robot = model.name.empty() ? fs::path(o.urdf).stem().string() : model.name;
  report.urdf = fs::path(o.urdf).filename().string();
  report.floating_base = o.floating_base;
  report.nq = model.nq;
  report.nv = model.nv;
  report.machine = cpuModel() + ", " + std::to_string(threads) + " hardware threads, " + today();
  char timing[400];
  std::snprintf(timing, sizeof timing,
                "median of %d batches of ~%g ms after a warm-up, thread CPU time (all-threads rows: wall clock), "
                "fixed random inputs%s; generated code: the median over %d copies of each library file (1 thread "
                "rows)",
                plan.batches, plan.batch_seconds * 1e3, o.quick ? " (--quick)" : "", o.copies);
  report.timing = timing;
  if (anchors)
    report.anchor_source =
        "../shared/notes/anchors.md (Pinocchio 3.7, CppADCodeGen 2.4, gcc 12 -O3 "
        "-march=native, 2-core Rocket Lake), µs per call";

  // Cold builds, one directory each.
  std::vector<Generated> gens;
  LibraryOptions lib_options;
  lib_options.compiler.jobs = 0;  // one per hardware thread
  for (const SpecText& s : kSpecs) {
    Generated g;
    g.name = s.name;
    g.label = s.label;
    g.spec = parseFunctionSpec(withBuild(s.json), std::string("bench:") + s.name);
    LibraryOptions options = lib_options;
    options.builder.name = s.name;
    progress("generating " + g.name + " ...");
    const auto t0 = std::chrono::steady_clock::now();
    g.lib = generateFunctionLibrary(model, g.spec, dir.path() / s.name, options);
    g.total_seconds = secondsSince(t0);
    g.process_peak_bytes = processPeakBytes();
    char line[200];
    std::snprintf(line, sizeof line, "  %.3f s (compile %.3f s), %u operations", g.total_seconds, g.lib.compile.seconds,
                  g.lib.info.operations);
    progress(line);
    g.copies.push_back(codegen::LoadedLibrary::open(g.lib.library).function(s.name));
    for (int c = 1; c < o.copies; ++c) {
      const fs::path copy = dir.path() / (std::string(s.name) + "_copy" + std::to_string(c) + ".so");
      fs::copy_file(g.lib.library, copy, fs::copy_options::overwrite_existing);
      g.copies.push_back(codegen::LoadedLibrary::open(copy).function(s.name));
    }
    gens.push_back(std::move(g));
  }
  auto gen = [&](const std::string& name) -> Generated& {
    for (Generated& g : gens)
      if (g.name == name) return g;
    throw std::logic_error("bench: no function " + name);
  };
  {
    const codegen::CompileReport& c = gens.front().lib.compile;
    std::string flags;
    for (const std::string& f : c.flags) flags += " " + f;
    report.code_flags = c.compiler + flags + " (" + std::string(codegen::kGeneratorVersion) + ")";
  }

  // Evaluation rows.
  std::vector<Row>& rows = report.evaluation;
  auto addRow = [&](Row r) {
    if (anchors) {
      if (auto it = anchors->text.find(r.name); it != anchors->text.end()) r.anchor = it->second;
      if (auto it = anchors->targets.find(r.name); it != anchors->targets.end()) r.target = it->second;
    }
    rows.push_back(std::move(r));
  };
  auto micros = [&](const std::string& name) {
    for (const Row& r : rows)
      if (r.name == name) return r.value;
    throw std::logic_error("bench: no row " + name);
  };
  auto ratio = [&](double value, const std::string& to) { return Ratio{to, value / micros(to)}; };
  auto timeRow = [&](const std::string& what) { progress("timing " + what + " ..."); };

  Generated& rnea_j = gen("rnea_jacobian_dense");
  Generated& aba_j = gen("aba_jacobian");
  Buffers rnea_state(model, rnea_j, 1, 0), aba_state(model, aba_j, 1, 0);
  const Eigen::VectorXd q = rnea_state.input(0), v = rnea_state.input(1), a = rnea_state.input(2);
  const Eigen::VectorXd qa = aba_state.input(0), va = aba_state.input(1), tau = aba_state.input(2);

  timeRow("double RNEA and ABA");
  Data<double> data(model);
  addRow(makeRow("rnea_double", "double RNEA (core/dynamics)", "double RNEA", Unit::Microseconds,
                 1e6 * secondsPerCall([&] { doNotOptimize(rnea(model, data, q, v, a)); }, plan)));
  {
    const double t = 1e6 * secondsPerCall([&] { doNotOptimize(aba(model, data, qa, va, tau)); }, plan);
    addRow(makeRow("aba_double", "double ABA (core/dynamics)", "double ABA", Unit::Microseconds, t,
                   {ratio(t, "rnea_double")}));
  }

  // Each generated function at one state.
  std::map<std::string, Buffers> single;
  for (Generated& g : gens) {
    timeRow("generated " + g.name);
    Buffers& b = single.emplace(g.name, Buffers(model, g, 1, g.fn().workSize())).first->second;
    const double t = 1e6 * medianOverCopies(g, [&](const codegen::CompiledFunction& f) {
                       return secondsPerCall(
                           [&] {
                             f.evaluate(b.in_ptr.data(), b.out_ptr.data(), b.work.data());
                             doNotOptimize(b.out_ptr[0][0]);
                           },
                           plan);
                     });
    g.fn().evaluate(b.in_ptr.data(), b.out_ptr.data(), b.work.data());  // the outputs the checks read
    Row r = makeRow(g.name, "generated " + g.label, "generated " + g.label, Unit::Microseconds, t);
    if (g.name == "rnea_jacobian_dense") r.short_label = "generated RNEA J";
    if (g.name == "aba_jacobian") r.short_label = "generated ABA J";
    if (g.name == "rnea_jacobian_sparse")
      r.label += " (" + std::to_string(g.lib.built.outputs.at(1).nnz) + " of " +
                 std::to_string(model.nv * 3 * model.nv) + " entries)";
    r.ratios.push_back(ratio(t, "rnea_double"));
    if (g.name.rfind("aba", 0) == 0) r.ratios.push_back(ratio(t, "aba_double"));
    if (g.name == "rnea_jacobian_sparse") r.ratios.push_back(ratio(t, "rnea_jacobian_dense"));
    addRow(std::move(r));
  }

  // The interpreter on both Jacobians.
  std::map<std::string, Eigen::VectorXd> interpreted;
  for (Generated* g : {&rnea_j, &aba_j}) {
    timeRow("interpreter on " + g->name);
    const codegen::Interpreter interp(*g->lib.built.graph, g->lib.built.definition);
    Buffers b(model, *g, 1, interp.workSize());
    const double t = 1e6 * secondsPerCall(
                               [&] {
                                 interp.evaluate(b.in_ptr.data(), b.out_ptr.data(), b.work.data());
                                 doNotOptimize(b.out_ptr[0][0]);
                               },
                               plan);
    interpreted[g->name] = b.output(1);
    Row r =
        makeRow("interpreter_" + g->name, "interpreter, " + g->label, "", Unit::Microseconds, t, {ratio(t, g->name)});
    r.target = Target{5.0, g->name, "<= 5x compiled"};
    addRow(std::move(r));
  }

  // Central finite differences of double RNEA.
  timeRow("finite differences");
  RneaFiniteDifferences fd(model, q, v, a);
  {
    const double t = 1e6 * secondsPerCall(
                               [&] {
                                 fd();
                                 doNotOptimize(fd.jacobian()(0, 0));
                               },
                               plan);
    addRow(makeRow("rnea_fd",
                   "central FD of double RNEA over [q,v,a] (" + std::to_string(6 * model.nv) + " RNEA calls)", "FD",
                   Unit::Microseconds, t, {ratio(t, "rnea_double")}));
    for (Row& r : rows)
      if (r.name == "rnea_jacobian_dense" || r.name == "rnea_jacobian_sparse")
        r.ratios.push_back(ratio(r.value, "rnea_fd"));
  }

  // Batches of 1,000 knots: one call of evaluateBatch on one thread; a slice per thread.
  for (Generated* g : {&rnea_j, &aba_j}) {
    timeRow("batch of " + std::to_string(kKnots) + " knots, " + g->name);
    const codegen::CompiledFunction& f = g->fn();
    Buffers b(model, *g, kKnots, f.batchWorkSize());
    const double per_batch = medianOverCopies(*g, [&](const codegen::CompiledFunction& copy) {
      return secondsPerCall(
          [&] {
            copy.evaluateBatch(kKnots, b.in_ptr.data(), b.out_ptr.data(), b.work.data());
            doNotOptimize(b.out_ptr[0][0]);
          },
          plan);
    });
    const double t1 = 1e6 * per_batch / kKnots;
    const std::string stem = g->name == "aba_jacobian" ? "ABA J" : "RNEA J";
    Row r1 = makeRow("batch_" + g->name + "_1_thread", "batch of 1000, " + stem + ", per knot, 1 thread", "",
                     Unit::Microseconds, t1, {ratio(t1, g->name)});
    r1.target = Target{0.4, g->name, "<= 0.4x one call"};
    addRow(std::move(r1));

    std::vector<std::vector<double>> work(threads, std::vector<double>(f.batchWorkSize()));
    const double tn = 1e6 * secondsPerKnotOnThreads(
                                [&](unsigned t, std::uint64_t begin, std::uint64_t end) {
                                  std::vector<const double*> in(b.in_ptr.size());
                                  std::vector<double*> out(b.out_ptr.size());
                                  for (std::size_t k = 0; k < in.size(); ++k)
                                    in[k] = b.in_ptr[k] + begin * b.in_size[k];
                                  for (std::size_t k = 0; k < out.size(); ++k)
                                    out[k] = b.out_ptr[k] + begin * b.out_size[k];
                                  f.evaluateBatch(end - begin, in.data(), out.data(), work[t].data());
                                },
                                threads, kKnots, per_batch, plan);
    addRow(makeRow("batch_" + g->name + "_all_threads",
                   "batch of 1000, " + stem + ", per knot, " + std::to_string(threads) + " threads", "",
                   Unit::Microseconds, tn, {ratio(tn, g->name)}));

    // The batch computes what single calls compute.
    double err = 0;
    const codegen::CompiledFunction& single_f = g->fn();
    Buffers one(model, *g, 1, single_f.workSize());
    for (std::uint64_t k = 0; k < kKnots; k += 97) {
      for (std::size_t blk = 0; blk < one.in.size(); ++blk) {
        const Eigen::VectorXd x = b.input(blk, k);
        std::copy(x.data(), x.data() + x.size(), one.in[blk].data());
      }
      single_f.evaluate(one.in_ptr.data(), one.out_ptr.data(), one.work.data());
      for (std::size_t blk = 0; blk < one.out.size(); ++blk)
        err = std::max(err, relativeError(b.output(blk, k), one.output(blk)));
    }
    report.checks["batch_vs_single_" + g->name] = err;
  }

  // Checks that the timed code computes the right thing (relative max errors).
  {
    const Buffers& dense = single.at("rnea_jacobian_dense");
    const Buffers& sparse = single.at("rnea_jacobian_sparse");
    const codegen::OutputBlock& jd = rnea_j.lib.built.definition.outputs.at(1);
    const codegen::OutputBlock& js = gen("rnea_jacobian_sparse").lib.built.definition.outputs.at(1);
    const Eigen::MatrixXd J = blockMatrix(jd, dense.output(1));
    report.checks["rnea_jacobian_vs_fd"] = relativeError(J, fd.jacobian());
    report.checks["rnea_jacobian_sparse_vs_dense"] = relativeError(blockMatrix(js, sparse.output(1)), J);
    report.checks["rnea_value_vs_double"] =
        relativeError(single.at("rnea_value").output(0), Eigen::VectorXd(rnea(model, data, q, v, a)));
    const Buffers& abav = single.at("aba_value");
    report.checks["aba_value_vs_double"] =
        relativeError(abav.output(0), Eigen::VectorXd(aba(model, data, abav.input(0), abav.input(1), abav.input(2))));
    report.checks["interpreter_vs_compiled_rnea_jacobian"] =
        relativeError(interpreted.at("rnea_jacobian_dense"), dense.output(1));
    report.checks["interpreter_vs_compiled_aba_jacobian"] =
        relativeError(interpreted.at("aba_jacobian"), single.at("aba_jacobian").output(1));
    for (auto it = report.checks.begin(); it != report.checks.end(); ++it) {
      const double err = it.value().get<double>(), limit = it.key() == "rnea_jacobian_vs_fd" ? 1e-5 : 1e-9;
      if (!(err <= limit))
        std::cerr << "bench: warning: check " << it.key() << " = " << err << " (limit " << limit << ")\n";
    }
  }

  // Generation rows.
  for (const Generated& g : gens) {
    report.generation_functions.push_back(g.name);
    const GeneratedFunctionLibrary& l = g.lib;
    auto add = [&](const std::string& field, Unit unit, double value) {
      Row r = makeRow("build." + g.name + "." + field, g.label + ": " + field, "", unit, value);
      r.group = g.name;
      r.field = field;
      if (anchors) {
        if (auto it = anchors->text.find(r.name); it != anchors->text.end()) r.anchor = it->second;
        if (auto it = anchors->targets.find(r.name); it != anchors->targets.end()) r.target = it->second;
      }
      if (field == "compiler_peak_memory" || field == "process_peak_memory")
        r.target = Target{1024.0 * 1024 * 1024, "", "< 1 GiB"};
      report.generation.push_back(std::move(r));
    };
    add("trace", Unit::Seconds, l.built.timings.trace_seconds);
    add("differentiate", Unit::Seconds, l.built.timings.differentiate_seconds);
    add("assemble", Unit::Seconds, l.built.timings.assemble_seconds);
    add("emit", Unit::Seconds, l.emit_seconds);
    add("compile", Unit::Seconds, l.compile.seconds);
    add("total", Unit::Seconds, g.total_seconds);
    add("compiler_peak_memory", Unit::Bytes, static_cast<double>(l.compile.peak_memory_bytes));
    add("process_peak_memory", Unit::Bytes, static_cast<double>(g.process_peak_bytes));
    add("operations", Unit::Count, l.info.operations);
    add("parts", Unit::Count, l.info.parts);
    add("source", Unit::Bytes, static_cast<double>(l.source_bytes));
    add("library", Unit::Bytes, static_cast<double>(l.library_bytes));
  }

  if (!o.keep.empty()) progress("libraries kept in " + dir.path().string());
  if (o.json)
    std::cout << report.toJson().dump(2) << "\n";
  else if (o.markdown)
    report.printMarkdown(std::cout);
  else
    report.printText(std::cout);
}

}  // namespace

void addBenchCommand(CLI::App& app) {
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "Benchmark generated RNEA / ABA functions and their Jacobians for one robot (builds them cold first)");
  cmd->add_option("--urdf", options->urdf, "Robot description (URDF file)")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--floating-base", options->floating_base, "Add a free-flyer root joint");
  auto* json = cmd->add_flag(
      "--json", options->json,
      "Print JSON: one entry per row (name, us_per_call / seconds / bytes / count, ratios, target, status)");
  auto* md = cmd->add_flag("--markdown", options->markdown, "Print markdown tables (for docs/benchmarks.md)");
  json->excludes(md);
  cmd->add_flag("--quick", options->quick, "Shorter timing (3 batches of ~3 ms instead of 7 of ~20 ms): noisier");
  cmd->add_option("--copies", options->copies,
                  "Time each generated library loaded from this many copies of its file and report the median "
                  "(identical bytes on other memory pages run up to 2x apart here)")
      ->check(CLI::Range(1, 15))
      ->capture_default_str();
  cmd->add_option("--keep", options->keep,
                  "Build the libraries in DIR and keep them (default: a temporary directory, removed)");
  cmd->callback([options] { run(*options); });
}

}  // namespace robodiff::cli
