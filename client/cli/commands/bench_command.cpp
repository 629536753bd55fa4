// `robodiff bench`: the benchmark table of one robot, reproducible from the command
// line. Builds (cold, into a temporary directory) RNEA value, RNEA value + Jacobian in
// [q, v, a] (dense and sparse), ABA value and ABA value + Jacobian in [q, v, tau], then
// times per call: double RNEA and ABA (core/dynamics), each generated function, the
// interpreter on both Jacobians, central finite differences of double RNEA, and batches
// of 1,000 knots on one thread and on every hardware thread. Ratios come from the same
// run; for the robots of ../shared/notes/anchors.md (Panda, UR5, Talos with a fixed
// base) the figures of Pinocchio and CppADCodeGen on this machine kind are shown, and
// the targets get PASS or MISS. `--spec FILE` adds a function of the user's
// own (bench_fixtures.hpp, userBenchSpecs): built, timed and checked against the
// interpreter like the rest. `--keep DIR --reuse` times again what an earlier run kept
// (options/kept_library.hpp), without building.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "commands/bench_fixtures.hpp"
#include "commands/bench_timing.hpp"
#include "commands/commands.hpp"
#include "options/kept_library.hpp"
#include "output/bench_report.hpp"
#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::cli {
namespace {

namespace fs = std::filesystem;
using namespace bench;

struct Options {
  std::string urdf, keep;
  std::vector<std::string> specs;  // --spec: user functions timed too
  bool floating_base = false, json = false, markdown = false, quick = false;
  bool reuse = false;  // --reuse: load what an earlier run kept in --keep DIR
  bool no_batch = false;  // --no-batch: every library built with "batch": false
  int copies = 3;
};

void progress(const std::string& s) { std::cerr << "bench: " << s << std::endl; }

// One `robodiff bench` run: builds the functions cold, then adds the report's rows step
// by step (each step may take ratios to the rows before it).
class BenchRun {
 public:
  explicit BenchRun(const Options& o)
      : o_(o),
        model_(loadUrdfFile(o.urdf, o.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed)),
        anchors_(anchorsFor(model_)),
        plan_(o.quick ? TimingPlan::quick() : TimingPlan::full()),
        threads_(hardwareThreads()),
        dir_(o.keep),
        data_(model_) {}

  void run() {
    describe();
    buildAll();
    prepareStates();
    timeDoubles();
    timeGenerated();
    timeInterpreter();
    timeFiniteDifferences();
    for (Generated* g : {&gen("rnea_jacobian_dense"), &gen("aba_jacobian")}) timeBatch(*g);
    checkResults();
    for (const Generated& g : gens_)
      if (!g.reused) addGenerationRows(g);
    if (!o_.keep.empty()) progress("libraries kept in " + dir_.path().string());
    if (o_.json) std::cout << report_.toJson().dump(2) << "\n";
    else if (o_.markdown) report_.printMarkdown(std::cout);
    else report_.printText(std::cout);
  }

 private:
  void describe() {
    report_.robot = model_.name.empty() ? fs::path(o_.urdf).stem().string() : model_.name;
    report_.urdf = fs::path(o_.urdf).filename().string();
    report_.floating_base = o_.floating_base;
    report_.nq = model_.nq;
    report_.nv = model_.nv;
    report_.machine = cpuModel() + ", " + std::to_string(threads_) + " hardware threads, " + today();
    char timing[400];
    std::snprintf(timing, sizeof timing,
                  "median of %d batches of ~%g ms after a warm-up, thread CPU time (all-threads rows: wall clock), "
                  "fixed random inputs%s; generated code: the median over %d copies of each library file (1 thread "
                  "rows)",
                  plan_.batches, plan_.batch_seconds * 1e3, o_.quick ? " (--quick)" : "", o_.copies);
    report_.timing = timing;
    if (anchors_)
      report_.anchor_source =
          "../shared/notes/anchors.md (Pinocchio 3.7, CppADCodeGen 2.4, gcc 12 -O3 "
          "-march=native, 2-core Rocket Lake), µs per call";
  }

  // Cold builds, one directory each; every library loaded from `copies` files.
  void buildAll() {
    // --spec functions first (a spec that cannot be built fails before the long builds),
    // listed after the built-in rows.
    std::vector<Generated> user;
    for (const BenchSpec& s : userBenchSpecs(o_.specs, builtinRowNames())) {
      user.push_back(build(s));
      user_names_.push_back(s.name);
    }
    for (const BenchSpec& s : builtinBenchSpecs()) gens_.push_back(build(s));
    for (Generated& g : user) gens_.push_back(std::move(g));
    const codegen::CompileReport& c = gens_.front().lib.compile;
    std::string flags;
    for (const std::string& f : c.flags) flags += " " + f;
    report_.code_flags = c.compiler + flags + " (" + std::string(codegen::kGeneratorVersion) + ")";
  }

  // Every row name a --spec row may not take.
  static std::vector<std::string> builtinRowNames() {
    std::vector<std::string> names = {"rnea_double", "aba_double", "rnea_fd"};
    for (const SpecText& s : kSpecs) {
      names.push_back(s.name);
      names.push_back(std::string("interpreter_") + s.name);
      names.push_back(std::string("batch_") + s.name + "_1_thread");
      names.push_back(std::string("batch_") + s.name + "_all_threads");
    }
    return names;
  }

  Generated build(const BenchSpec& s) {
    Generated g;
    g.name = s.name;
    g.label = s.label;
    g.spec = parseFunctionSpec(s.json, s.source);
    if (o_.no_batch) g.spec.build.batch = false;
    LibraryOptions options;
    options.compiler.jobs = 0;  // one per hardware thread
    options.builder.name = s.name;
    std::optional<GeneratedFunctionLibrary> kept;
    if (o_.reuse) kept = keptLibrary(model_, g.spec, dir_.path() / s.name, options);
    if (kept) {
      g.lib = std::move(*kept);
      g.reused = true;
      progress("reusing the kept " + g.name + " (" + std::to_string(g.lib.info.operations) + " operations)");
    } else {
      progress("generating " + g.name + " ...");
      const auto t0 = std::chrono::steady_clock::now();
      g.lib = generateFunctionLibrary(model_, g.spec, dir_.path() / s.name, options);
      g.total_seconds = secondsSince(t0);
      g.process_peak_bytes = processPeakBytes();
      char line[200];
      std::snprintf(line, sizeof line, "  %.3f s (compile %.3f s), %u operations", g.total_seconds,
                    g.lib.compile.seconds, g.lib.info.operations);
      progress(line);
    }
    g.copies.push_back(codegen::LoadedLibrary::open(g.lib.library).function(s.name));
    for (int c = 1; c < o_.copies; ++c) {
      const fs::path copy = dir_.path() / (s.name + "_copy" + std::to_string(c) + ".so");
      fs::copy_file(g.lib.library, copy, fs::copy_options::overwrite_existing);
      g.copies.push_back(codegen::LoadedLibrary::open(copy).function(s.name));
    }
    return g;
  }

  Generated& gen(const std::string& name) {
    for (Generated& g : gens_)
      if (g.name == name) return g;
    throw std::logic_error("bench: no function " + name);
  }

  // The states the double functions and the finite differences are timed at: the
  // generated RNEA's and ABA's first knots.
  void prepareStates() {
    const Buffers rnea_state(model_, gen("rnea_jacobian_dense"), 1, 0);
    const Buffers aba_state(model_, gen("aba_jacobian"), 1, 0);
    q_ = rnea_state.input(0), v_ = rnea_state.input(1), a_ = rnea_state.input(2);
    qa_ = aba_state.input(0), va_ = aba_state.input(1), tau_ = aba_state.input(2);
  }

  void addRow(Row r) {
    if (anchors_) {
      if (auto it = anchors_->text.find(r.name); it != anchors_->text.end()) r.anchor = it->second;
      if (auto it = anchors_->targets.find(r.name); it != anchors_->targets.end()) r.target = it->second;
    }
    report_.evaluation.push_back(std::move(r));
  }
  double micros(const std::string& name) const {
    for (const Row& r : report_.evaluation)
      if (r.name == name) return r.value;
    throw std::logic_error("bench: no row " + name);
  }
  Ratio ratio(double value, const std::string& to) const { return Ratio{to, value / micros(to)}; }

  void timeDoubles() {
    progress("timing double RNEA and ABA ...");
    addRow(makeRow("rnea_double", "double RNEA (core/dynamics)", "double RNEA", Unit::Microseconds,
                   1e6 * secondsPerCall([&] { doNotOptimize(rnea(model_, data_, q_, v_, a_)); }, plan_)));
    const double t = 1e6 * secondsPerCall([&] { doNotOptimize(aba(model_, data_, qa_, va_, tau_)); }, plan_);
    addRow(makeRow("aba_double", "double ABA (core/dynamics)", "double ABA", Unit::Microseconds, t,
                   {ratio(t, "rnea_double")}));
  }

  // Each generated function at one state; its outputs kept for the checks.
  void timeGenerated() {
    for (Generated& g : gens_) {
      progress("timing generated " + g.name + " ...");
      Buffers& b = single_.emplace(g.name, Buffers(model_, g, 1, g.fn().workSize())).first->second;
      const double t = 1e6 * medianOverCopies(g, [&](const codegen::CompiledFunction& f) {
                         return secondsPerCall(
                             [&] {
                               f.evaluate(b.in_ptr.data(), b.out_ptr.data(), b.work.data());
                               doNotOptimize(b.out_ptr[0][0]);
                             },
                             plan_);
                       });
      g.fn().evaluate(b.in_ptr.data(), b.out_ptr.data(), b.work.data());
      addRow(generatedRow(g, t));
    }
  }

  Row generatedRow(const Generated& g, double t) const {
    Row r = makeRow(g.name, "generated " + g.label, "generated " + g.label, Unit::Microseconds, t);
    if (g.name == "rnea_jacobian_dense") r.short_label = "generated RNEA J";
    if (g.name == "aba_jacobian") r.short_label = "generated ABA J";
    if (g.name == "rnea_jacobian_sparse")
      r.label += " (" + std::to_string(g.lib.built.outputs.at(1).nnz) + " of " +
                 std::to_string(model_.nv * 3 * model_.nv) + " entries)";
    r.ratios.push_back(ratio(t, "rnea_double"));
    if (g.name.rfind("aba", 0) == 0) r.ratios.push_back(ratio(t, "aba_double"));
    if (g.name == "rnea_jacobian_sparse") r.ratios.push_back(ratio(t, "rnea_jacobian_dense"));
    return r;
  }

  // The interpreter on both Jacobians.
  void timeInterpreter() {
    for (Generated* g : {&gen("rnea_jacobian_dense"), &gen("aba_jacobian")}) {
      progress("timing interpreter on " + g->name + " ...");
      const codegen::Interpreter interp(*g->lib.built.graph, g->lib.built.definition);
      Buffers b(model_, *g, 1, interp.workSize());
      const double t = 1e6 * secondsPerCall(
                                 [&] {
                                   interp.evaluate(b.in_ptr.data(), b.out_ptr.data(), b.work.data());
                                   doNotOptimize(b.out_ptr[0][0]);
                                 },
                                 plan_);
      interpreted_[g->name] = b.output(1);
      Row r = makeRow("interpreter_" + g->name, "interpreter, " + g->label, "", Unit::Microseconds, t,
                      {ratio(t, g->name)});
      r.target = Target{5.0, g->name, "<= 5x compiled"};
      addRow(std::move(r));
    }
  }

  // Central finite differences of double RNEA.
  void timeFiniteDifferences() {
    progress("timing finite differences ...");
    fd_ = std::make_unique<RneaFiniteDifferences>(model_, q_, v_, a_);
    RneaFiniteDifferences& fd = *fd_;
    const double t = 1e6 * secondsPerCall(
                               [&] {
                                 fd();
                                 doNotOptimize(fd.jacobian()(0, 0));
                               },
                               plan_);
    addRow(makeRow("rnea_fd",
                   "central FD of double RNEA over [q,v,a] (" + std::to_string(6 * model_.nv) + " RNEA calls)", "FD",
                   Unit::Microseconds, t, {ratio(t, "rnea_double")}));
    for (Row& r : report_.evaluation)
      if (r.name == "rnea_jacobian_dense" || r.name == "rnea_jacobian_sparse")
        r.ratios.push_back(ratio(r.value, "rnea_fd"));
  }

  // A batch of 1,000 knots: one evaluateBatch call on one thread, then a slice per
  // thread; and a check that the batch computes what single calls compute.
  void timeBatch(const Generated& g) {
    progress("timing batch of " + std::to_string(kKnots) + " knots, " + g.name + " ...");
    const codegen::CompiledFunction& f = g.fn();
    Buffers b(model_, g, kKnots, f.batchWorkSize());
    const double per_batch = medianOverCopies(g, [&](const codegen::CompiledFunction& copy) {
      return secondsPerCall(
          [&] {
            copy.evaluateBatch(kKnots, b.in_ptr.data(), b.out_ptr.data(), b.work.data());
            doNotOptimize(b.out_ptr[0][0]);
          },
          plan_);
    });
    const double t1 = 1e6 * per_batch / kKnots;
    const std::string stem = g.name == "aba_jacobian" ? "ABA J" : "RNEA J";
    Row r1 = makeRow("batch_" + g.name + "_1_thread", "batch of 1000, " + stem + ", per knot, 1 thread", "",
                     Unit::Microseconds, t1, {ratio(t1, g.name)});
    r1.target = Target{0.4, g.name, "<= 0.4x one call"};
    addRow(std::move(r1));
    const double tn = 1e6 * secondsPerKnotOnAllThreads(f, b, per_batch);
    addRow(makeRow("batch_" + g.name + "_all_threads",
                   "batch of 1000, " + stem + ", per knot, " + std::to_string(threads_) + " threads", "",
                   Unit::Microseconds, tn, {ratio(tn, g.name)}));
    report_.checks["batch_vs_single_" + g.name] = batchAgainstSingleCalls(g, b);
  }

  double secondsPerKnotOnAllThreads(const codegen::CompiledFunction& f, const Buffers& b, double per_batch) {
    std::vector<std::vector<double>> work(threads_, std::vector<double>(f.batchWorkSize()));
    return secondsPerKnotOnThreads(
        [&](unsigned t, std::uint64_t begin, std::uint64_t end) {
          std::vector<const double*> in(b.in_ptr.size());
          std::vector<double*> out(b.out_ptr.size());
          for (std::size_t k = 0; k < in.size(); ++k) in[k] = b.in_ptr[k] + begin * b.in_size[k];
          for (std::size_t k = 0; k < out.size(); ++k) out[k] = b.out_ptr[k] + begin * b.out_size[k];
          f.evaluateBatch(end - begin, in.data(), out.data(), work[t].data());
        },
        threads_, kKnots, per_batch, plan_);
  }

  // The largest relative error of the batch's outputs against single calls (every 97th knot).
  double batchAgainstSingleCalls(const Generated& g, const Buffers& b) {
    double err = 0;
    Buffers one(model_, g, 1, g.fn().workSize());
    for (std::uint64_t k = 0; k < kKnots; k += 97) {
      for (std::size_t blk = 0; blk < one.in.size(); ++blk) {
        const Eigen::VectorXd x = b.input(blk, k);
        std::copy(x.data(), x.data() + x.size(), one.in[blk].data());
      }
      g.fn().evaluate(one.in_ptr.data(), one.out_ptr.data(), one.work.data());
      for (std::size_t blk = 0; blk < one.out.size(); ++blk)
        err = std::max(err, relativeError(b.output(blk, k), one.output(blk)));
    }
    return err;
  }

  // Checks that the timed code computes the right thing (relative max errors).
  void checkResults() {
    const Buffers& dense = single_.at("rnea_jacobian_dense");
    const Buffers& sparse = single_.at("rnea_jacobian_sparse");
    const codegen::OutputBlock& jd = gen("rnea_jacobian_dense").lib.built.definition.outputs.at(1);
    const codegen::OutputBlock& js = gen("rnea_jacobian_sparse").lib.built.definition.outputs.at(1);
    const Eigen::MatrixXd J = blockMatrix(jd, dense.output(1));
    auto& checks = report_.checks;
    checks["rnea_jacobian_vs_fd"] = relativeError(J, fd_->jacobian());
    checks["rnea_jacobian_sparse_vs_dense"] = relativeError(blockMatrix(js, sparse.output(1)), J);
    checks["rnea_value_vs_double"] =
        relativeError(single_.at("rnea_value").output(0), Eigen::VectorXd(rnea(model_, data_, q_, v_, a_)));
    const Buffers& abav = single_.at("aba_value");
    checks["aba_value_vs_double"] = relativeError(
        abav.output(0), Eigen::VectorXd(aba(model_, data_, abav.input(0), abav.input(1), abav.input(2))));
    checks["interpreter_vs_compiled_rnea_jacobian"] =
        relativeError(interpreted_.at("rnea_jacobian_dense"), dense.output(1));
    checks["interpreter_vs_compiled_aba_jacobian"] =
        relativeError(interpreted_.at("aba_jacobian"), single_.at("aba_jacobian").output(1));
    for (const std::string& name : user_names_)
      checks["interpreter_vs_compiled_" + name] = userAgainstInterpreter(gen(name));
    for (auto it = checks.begin(); it != checks.end(); ++it) {
      const double err = it.value().get<double>(), limit = it.key() == "rnea_jacobian_vs_fd" ? 1e-5 : 1e-9;
      if (!(err <= limit))
        std::cerr << "bench: warning: check " << it.key() << " = " << err << " (limit " << limit << ")\n";
    }
  }

  // The largest relative error of a --spec function's compiled outputs (at the timed
  // state) against the interpreter's, over every output block.
  double userAgainstInterpreter(const Generated& g) {
    const codegen::Interpreter interp(*g.lib.built.graph, g.lib.built.definition);
    const Buffers& compiled = single_.at(g.name);
    Buffers b(model_, g, 1, interp.workSize());
    interp.evaluate(b.in_ptr.data(), b.out_ptr.data(), b.work.data());
    double err = 0;
    for (std::size_t blk = 0; blk < b.out.size(); ++blk)
      err = std::max(err, relativeError(compiled.output(blk), b.output(blk)));
    return err;
  }

  void addGenerationRows(const Generated& g) {
    report_.generation_functions.push_back(g.name);
    const GeneratedFunctionLibrary& l = g.lib;
    auto add = [&](const std::string& field, Unit unit, double value) {
      Row r = makeRow("build." + g.name + "." + field, g.label + ": " + field, "", unit, value);
      r.group = g.name;
      r.field = field;
      if (anchors_) {
        if (auto it = anchors_->text.find(r.name); it != anchors_->text.end()) r.anchor = it->second;
        if (auto it = anchors_->targets.find(r.name); it != anchors_->targets.end()) r.target = it->second;
      }
      if (field == "compiler_peak_memory" || field == "process_peak_memory")
        r.target = Target{1024.0 * 1024 * 1024, "", "< 1 GiB"};
      report_.generation.push_back(std::move(r));
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

  const Options& o_;
  const Model model_;
  const std::optional<Anchors> anchors_;
  const TimingPlan plan_;
  const unsigned threads_;
  WorkDir dir_;
  Data<double> data_;
  Report report_;
  std::vector<Generated> gens_;
  std::vector<std::string> user_names_;                 // the --spec rows
  Eigen::VectorXd q_, v_, a_, qa_, va_, tau_;
  std::map<std::string, Buffers> single_;                // each function's buffers at one state
  std::map<std::string, Eigen::VectorXd> interpreted_;  // the interpreter's Jacobians
  std::unique_ptr<RneaFiniteDifferences> fd_;
};

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
  cmd->add_option("--spec", options->specs,
                  "Also build and time this function spec (repeatable; a user function, docs/function-language.md, "
                  "or a built-in one): row NAME (the spec's \"name\", else the file's stem) with every output, and "
                  "NAME_value with its value outputs alone when it has others; each with its build rows, and checked "
                  "against the interpreter (checks.interpreter_vs_compiled_NAME)")
      ->type_name("SPEC.json")
      ->check(CLI::ExistingFile);
  auto* keep = cmd->add_option("--keep", options->keep,
                               "Build the libraries in DIR and keep them (default: a temporary directory, removed)");
  cmd->add_flag("--reuse", options->reuse,
                "Load each library an earlier run kept in --keep DIR when it is the one this run would build (same "
                "spec, same generated C) instead of building it again; a reused library has no build rows")
      ->needs(keep);
  cmd->add_flag("--no-batch", options->no_batch,
                "Build every library with \"batch\": false: the single-knot code alone, in about half the time (how "
                "bench/anchors compares builds with CppADCodeGen's, which have no batched code); the batch rows "
                "then time it knot by knot");
  cmd->callback([options] { BenchRun(*options).run(); });
}

}  // namespace robodiff::cli
