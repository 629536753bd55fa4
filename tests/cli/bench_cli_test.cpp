// `robodiff bench` as a user runs it: real processes on small generated chains
// (--quick; every build is compiled cold, so the robots are kept small for the test's
// time), the JSON parsed back. Checks that every row of the table is there with a
// sane number, that the timed code computed the right thing, and the orderings that
// hold on any machine however noisy (compiled code beats the interpreter and finite
// differences by wide margins); the issue's targets themselves are for the README run.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>

#include "support/process.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::cliPath;
using testing::runCommand;
using testing::shellQuote;

namespace fs = std::filesystem;

std::string bench(const fs::path& urdf, const std::string& args) {
  return shellQuote(cliPath().string()) + " bench --urdf " + shellQuote(urdf.string()) + " " + args;
}

// A scratch directory with a generated chain of n joints in it, chain<n>.urdf.
class ChainDir {
 public:
  explicit ChainDir(int n)
      : dir_(fs::temp_directory_path() /
             ("robodiff-bench-test-" + std::to_string(::getpid()) + "-" + std::to_string(n))),
        urdf_(dir_ / ("chain" + std::to_string(n) + ".urdf")) {
    fs::create_directories(dir_);
    const testing::ProcessResult made = runCommand(shellQuote(cliPath().string()) + " make-robot --chain " +
                                                   std::to_string(n) + " --out " + shellQuote(urdf_.string()));
    EXPECT_EQ(made.exit_code, 0) << made.err;
  }
  ~ChainDir() { fs::remove_all(dir_); }
  const fs::path& dir() const { return dir_; }
  const fs::path& urdf() const { return urdf_; }

 private:
  fs::path dir_, urdf_;
};

const nlohmann::json* findRow(const nlohmann::json& rows, const std::string& name) {
  for (const nlohmann::json& r : rows)
    if (r.at("name") == name) return &r;
  return nullptr;
}

double number(const nlohmann::json& row) {
  for (const char* key : {"us_per_call", "seconds", "bytes", "count"})
    if (row.contains(key)) return row.at(key).get<double>();
  ADD_FAILURE() << "row " << row.at("name") << " has no value: " << row.dump();
  return NAN;
}

TEST(BenchCli, QuickJsonHasEveryRowAndSaneFigures) {
  const ChainDir chain(4);
  const testing::ProcessResult r = runCommand(bench(chain.urdf(), "--json --quick"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("robot"), "chain4");
  EXPECT_EQ(j.at("nq"), 4);
  EXPECT_EQ(j.at("nv"), 4);
  EXPECT_EQ(j.at("floating_base"), false);
  const nlohmann::json& rows = j.at("rows");

  const std::vector<std::string> per_call = {"rnea_double",
                                             "aba_double",
                                             "rnea_value",
                                             "rnea_jacobian_dense",
                                             "rnea_jacobian_sparse",
                                             "aba_value",
                                             "aba_jacobian",
                                             "interpreter_rnea_jacobian_dense",
                                             "interpreter_aba_jacobian",
                                             "rnea_fd",
                                             "batch_rnea_jacobian_dense_1_thread",
                                             "batch_rnea_jacobian_dense_all_threads",
                                             "batch_aba_jacobian_1_thread",
                                             "batch_aba_jacobian_all_threads"};
  for (const std::string& name : per_call) {
    const nlohmann::json* row = findRow(rows, name);
    ASSERT_NE(row, nullptr) << "no row " << name;
    ASSERT_TRUE(row->contains("us_per_call")) << row->dump();
    const double t = row->at("us_per_call").get<double>();
    EXPECT_TRUE(std::isfinite(t) && t > 0) << name << " = " << t;
    EXPECT_LT(t, 1e5) << name;  // microseconds: a 4-joint chain's function never takes 0.1 s
    if (row->contains("ratios"))
      for (const auto& [to, ratio] : row->at("ratios").items()) {
        EXPECT_NE(findRow(rows, to), nullptr) << name << " has a ratio to an unknown row " << to;
        EXPECT_TRUE(std::isfinite(ratio.get<double>()) && ratio.get<double>() > 0) << name << " / " << to;
      }
  }

  const std::vector<std::string> functions = {"rnea_value", "rnea_jacobian_dense", "rnea_jacobian_sparse", "aba_value",
                                              "aba_jacobian"};
  const std::vector<std::string> seconds = {"trace", "differentiate", "assemble", "emit", "compile", "total"};
  const std::vector<std::string> bytes = {"compiler_peak_memory", "process_peak_memory", "source", "library"};
  for (const std::string& f : functions) {
    double parts_sum = 0;
    for (const std::string& field : seconds) {
      const nlohmann::json* row = findRow(rows, "build." + f + "." + field);
      ASSERT_NE(row, nullptr) << "no row build." << f << "." << field;
      ASSERT_TRUE(row->contains("seconds")) << row->dump();
      const double s = row->at("seconds").get<double>();
      EXPECT_TRUE(std::isfinite(s) && s >= 0) << f << "." << field << " = " << s;
      if (field != "total") parts_sum += s;
    }
    EXPECT_GT(number(*findRow(rows, "build." + f + ".compile")), 0) << f;
    EXPECT_GE(number(*findRow(rows, "build." + f + ".total")) * 1.001 + 1e-3, parts_sum) << f;
    for (const std::string& field : bytes) {
      const nlohmann::json* row = findRow(rows, "build." + f + "." + field);
      ASSERT_NE(row, nullptr) << "no row build." << f << "." << field;
      ASSERT_TRUE(row->contains("bytes")) << row->dump();
      EXPECT_GT(row->at("bytes").get<double>(), 0) << f << "." << field;
    }
    for (const char* field : {"operations", "parts"}) {
      const nlohmann::json* row = findRow(rows, "build." + f + "." + field);
      ASSERT_NE(row, nullptr) << "no row build." << f << "." << field;
      EXPECT_GE(number(*row), 1) << f << "." << field;
    }
  }
  // One row per figure, no duplicates.
  std::set<std::string> names;
  for (const nlohmann::json& row : rows) EXPECT_TRUE(names.insert(row.at("name")).second) << row.at("name");
  EXPECT_EQ(names.size(), per_call.size() + functions.size() * (seconds.size() + bytes.size() + 2));

  // What was timed computed the right thing.
  const nlohmann::json& checks = j.at("checks");
  EXPECT_LT(checks.at("rnea_jacobian_vs_fd").get<double>(), 1e-5);
  for (const char* name : {"rnea_jacobian_sparse_vs_dense", "rnea_value_vs_double", "aba_value_vs_double",
                           "interpreter_vs_compiled_rnea_jacobian", "interpreter_vs_compiled_aba_jacobian",
                           "batch_vs_single_rnea_jacobian_dense", "batch_vs_single_aba_jacobian"})
    EXPECT_LT(checks.at(name).get<double>(), 1e-9) << name;

  // Orderings that survive a busy machine.
  auto us = [&](const std::string& name) { return findRow(rows, name)->at("us_per_call").get<double>(); };
  EXPECT_LT(us("rnea_jacobian_dense"), us("interpreter_rnea_jacobian_dense"));
  EXPECT_LT(us("aba_jacobian"), us("interpreter_aba_jacobian"));
  EXPECT_LT(us("rnea_jacobian_dense"), us("rnea_fd"));  // 24 RNEA calls
  EXPECT_LT(us("rnea_value"), us("rnea_jacobian_dense"));
  EXPECT_LT(us("aba_value"), us("aba_jacobian"));
  // Ratios are this row / the named row.
  const nlohmann::json& jr = findRow(rows, "rnea_jacobian_dense")->at("ratios");
  EXPECT_NEAR(jr.at("rnea_fd").get<double>(), us("rnea_jacobian_dense") / us("rnea_fd"), 1e-9);
  // Targets that apply to every robot come with a status; a generated chain has no anchors.
  const nlohmann::json& interp = *findRow(rows, "interpreter_rnea_jacobian_dense");
  ASSERT_TRUE(interp.contains("target"));
  EXPECT_TRUE(interp.at("status") == "PASS" || interp.at("status") == "MISS");
  EXPECT_FALSE(findRow(rows, "rnea_jacobian_dense")->contains("target"));
  EXPECT_FALSE(findRow(rows, "rnea_jacobian_dense")->contains("anchor"));
}

TEST(BenchCli, MarkdownAndKeptLibrariesForASmallChain) {
  const ChainDir chain(2);
  const fs::path keep = chain.dir() / "libs";
  const testing::ProcessResult r =
      runCommand(bench(chain.urdf(), "--markdown --quick --keep " + shellQuote(keep.string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("### chain2 (fixed base, nq = 2, nv = 2)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| generated RNEA + Jacobian [q,v,a], dense |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| rnea_jacobian_sparse |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("|---|"), std::string::npos) << r.out;
  for (const char* f : {"rnea_value", "rnea_jacobian_dense", "rnea_jacobian_sparse", "aba_value", "aba_jacobian"})
    EXPECT_TRUE(fs::exists(keep / f / (std::string(f) + ".so"))) << f;
}

// --keep DIR --reuse: a second run loads the libraries the first kept (it says so, and has
// no build rows) and times them; a kept source that no longer matches what this run
// generates is built again; --reuse without --keep is refused naming --keep.
TEST(BenchCli, ReuseLoadsWhatAnEarlierRunKeptOnlyWhenItsSourcesMatch) {
  const ChainDir chain(2);
  const fs::path keep = chain.dir() / "libs";
  const std::string kept = " --keep " + shellQuote(keep.string());
  testing::ProcessResult r = runCommand(bench(chain.urdf(), "--json --quick --copies 1" + kept));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(findRow(nlohmann::json::parse(r.out).at("rows"), "build.aba_jacobian.total"), nullptr);
  {  // one kept source spoiled: that library is built again, the others are reused
    std::ofstream spoil(keep / "aba_value" / "src" / "library.c", std::ios::app);
    spoil << "/* changed */\n";
  }
  r = runCommand(bench(chain.urdf(), "--json --quick --copies 1 --reuse" + kept));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("reusing the kept rnea_jacobian_dense"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("generating aba_value"), std::string::npos) << r.err;
  const nlohmann::json rows = nlohmann::json::parse(r.out).at("rows");
  EXPECT_EQ(findRow(rows, "build.rnea_jacobian_dense.total"), nullptr);
  EXPECT_NE(findRow(rows, "build.aba_value.total"), nullptr);
  ASSERT_NE(findRow(rows, "rnea_jacobian_dense"), nullptr);
  EXPECT_GT(number(*findRow(rows, "rnea_jacobian_dense")), 0.0);
  EXPECT_LE(nlohmann::json::parse(r.out).at("checks").at("interpreter_vs_compiled_rnea_jacobian").get<double>(), 1e-9);
  r = runCommand(bench(chain.urdf(), "--quick --reuse"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--keep"), std::string::npos) << r.err;
}

// --no-batch: every library is built with "batch": false (no SIMD batched code); the
// batch rows still agree with single calls.
TEST(BenchCli, NoBatchBuildsTheSingleKnotCodeAlone) {
  const ChainDir chain(2);
  const fs::path keep = chain.dir() / "libs";
  const testing::ProcessResult r =
      runCommand(bench(chain.urdf(), "--json --quick --copies 1 --no-batch --keep " + shellQuote(keep.string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f : {"rnea_value", "aba_jacobian"}) {
    std::ifstream description(keep / f / (std::string(f) + ".json"));
    const nlohmann::json d = nlohmann::json::parse(description);
    EXPECT_EQ(d.at("spec").at("build").value("batch", true), false) << f;
    // Assembly (single-knot code only, docs/code-generation.md) where the host runs it,
    // else C without its vector variant.
    if (fs::exists(keep / f / "src" / "library.s")) continue;
    EXPECT_FALSE(std::string(f) == "rnea_value" && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
        << "a small value function for this CPU is assembled";
    std::ifstream source(keep / f / "src" / "library.c");
    const std::string text((std::istreambuf_iterator<char>(source)), {});
    EXPECT_NE(text.find("#define RD_VECTOR 0"), std::string::npos) << f;
  }
  EXPECT_LE(nlohmann::json::parse(r.out).at("checks").at("batch_vs_single_aba_jacobian").get<double>(), 1e-12);
}

// The blocks of two compute outputs agree to 1e-10 (relative, or absolute below 1).
void expectSameNumbers(const nlohmann::json& a, const nlohmann::json& b, std::initializer_list<const char*> blocks) {
  for (const char* block : blocks) {
    const nlohmann::json x = a.at(block).flatten(), y = b.at(block).flatten();
    ASSERT_EQ(x.size(), y.size()) << block;
    for (auto it = x.begin(); it != x.end(); ++it) {
      const double expected = y.at(it.key()).get<double>();
      EXPECT_NEAR(it->get<double>(), expected, 1e-10 * (1 + std::abs(expected))) << block << it.key();
    }
  }
}

// `compute --backend generated --kept DIR/<row>` evaluates the library bench kept (what it
// timed) when it is this spec's and robot's, with the reference backend's numbers; a spec
// that builds another library, a directory with no kept library and another backend are
// refused, named. A user spec's kept library has its inputs in the order the file gives
// them (its blocks), not sorted by name.
TEST(BenchCli, ComputeLoadsAKeptLibraryOnlyWhenItIsTheSpecs) {
  const ChainDir chain(2);
  const fs::path keep = chain.dir() / "libs", step = chain.dir() / "step.json";
  std::ofstream(step) << R"json({"name": "step", "inputs": {"q": "configuration", "v": "nv", "u": "nv"},
    "define": {"v_next": "v + 0.01 * aba(q, v, u)"},
    "outputs": [{"name": "v_next", "kind": "value", "of": "v_next"},
                {"name": "dv", "kind": "jacobian", "of": "v_next", "wrt": ["v", "u"]}], "build": {"batch": false}})json";
  testing::ProcessResult r = runCommand(bench(chain.urdf(), "--json --quick --copies 1 --no-batch --spec " +
                                              shellQuote(step.string()) + " --keep " + shellQuote(keep.string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string step_compute = shellQuote(cliPath().string()) + " compute --urdf " +
                                   shellQuote(chain.urdf().string()) + " --random-state 4 --spec " +
                                   shellQuote(step.string()) + " --backend ";
  r = runCommand(step_compute + "generated --kept " + shellQuote((keep / "step").string()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json step_kept = nlohmann::json::parse(r.out);
  r = runCommand(step_compute + "interpreted");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json step_interpreted = nlohmann::json::parse(r.out);
  expectSameNumbers(step_kept, step_interpreted, {"v_next", "dv"});
  const fs::path spec = chain.dir() / "rnea_jacobian.json", batched = chain.dir() / "batched.json";
  std::ofstream(spec) << R"({"function": "rnea", "outputs": [{"kind": "value"},
    {"kind": "jacobian", "wrt": ["q", "v", "a"]}], "build": {"batch": false}})";
  std::ofstream(batched) << R"({"function": "rnea", "outputs": [{"kind": "value"},
    {"kind": "jacobian", "wrt": ["q", "v", "a"]}]})";
  const std::string compute = shellQuote(cliPath().string()) + " compute --urdf " + shellQuote(chain.urdf().string()) +
                              " --derivatives --random-state 3 --spec ";
  const std::string kept = " --backend generated --kept " + shellQuote((keep / "rnea_jacobian_dense").string());
  r = runCommand(compute + shellQuote(spec.string()) + kept);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json from_kept = nlohmann::json::parse(r.out);
  EXPECT_EQ(from_kept.at("cache"), "kept");
  r = runCommand(compute + shellQuote(spec.string()) + " --backend reference");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json reference = nlohmann::json::parse(r.out);
  expectSameNumbers(from_kept, reference, {"value", "jacobian"});
  r = runCommand(compute + shellQuote(batched.string()) + kept);  // the batched build is another library
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("is not the library this spec and robot build"), std::string::npos) << r.err;
  r = runCommand(compute + shellQuote(spec.string()) + " --backend generated --kept " + shellQuote(keep.string()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("no kept library"), std::string::npos) << r.err;
  r = runCommand(compute + shellQuote(spec.string()) + kept.substr(std::string(" --backend generated").size()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--backend generated"), std::string::npos) << r.err;
}

// --copies N: each library is loaded from N files (the built one and N - 1 copies of
// it), the timing line says the rows are medians over them, and a count out of range is
// refused naming the option.
TEST(BenchCli, TimesEachLibraryFromItsCopies) {
  const ChainDir chain(2);
  const fs::path keep = chain.dir() / "libs";
  testing::ProcessResult r =
      runCommand(bench(chain.urdf(), "--quick --copies 2 --keep " + shellQuote(keep.string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("the median over 2 copies of each library file"), std::string::npos) << r.out;
  for (const char* f : {"rnea_value", "rnea_jacobian_dense", "aba_jacobian"}) {
    EXPECT_TRUE(fs::exists(keep / (std::string(f) + "_copy1.so"))) << f;
    EXPECT_FALSE(fs::exists(keep / (std::string(f) + "_copy2.so"))) << f;
  }
  r = runCommand(bench(chain.urdf(), "--quick --copies 0"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--copies"), std::string::npos) << r.err;
}

// --spec FILE: a user function timed beside the built-in rows (row NAME with every output,
// NAME_value with its values alone), with its build rows and a check against the
// interpreter; a spec of values only gets one row; a built-in spec is named by its file.
TEST(BenchCli, TimesUserSpecsGivenWithSpec) {
  const fs::path urdf = testing::sourceDir() / "examples" / "robots" / "arm7.urdf";
  const ChainDir scratch(1);  // only its directory
  const fs::path knot = scratch.dir() / "knot.json", values = scratch.dir() / "values.json",
                 crba = scratch.dir() / "mass-matrix.json";
  std::ofstream(knot) << R"json({"name": "knot", "inputs": {"q": "configuration", "v": "nv", "u": "nv",
      "dt": {"fixed": [0.01]}, "target": {"fixed": [0.4, 0.1, 0.5]}},
    "define": {"v_next": "v + dt * aba(q, v, u)", "l": "sumsq(frame_position(q, 'link7') - target) + 1e-3 * sumsq(u)"},
    "outputs": [{"name": "v_next", "kind": "value", "of": "v_next"}, {"name": "l", "kind": "value", "of": "l"},
      {"name": "dv_next", "kind": "jacobian", "of": "v_next", "wrt": ["q", "v", "u"]},
      {"name": "grad", "kind": "gradient", "of": "l", "wrt": ["q", "u"]}]})json";
  std::ofstream(values) << R"json({"name": "values_only", "inputs": {"q": "configuration"},
    "outputs": [{"name": "p", "kind": "value", "of": "frame_position(q, 'link7')"}]})json";
  std::ofstream(crba) << R"json({"function": "crba", "outputs": [{"kind": "value"}]})json";
  const testing::ProcessResult r = runCommand(bench(urdf, "--json --quick --spec " + shellQuote(knot.string()) +
                                                              " --spec " + shellQuote(values.string()) + " --spec " +
                                                              shellQuote(crba.string())));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const nlohmann::json& rows = j.at("rows");
  for (const char* name : {"knot", "knot_value", "values_only", "mass_matrix"}) {
    const nlohmann::json* row = findRow(rows, name);
    ASSERT_NE(row, nullptr) << "no row " << name;
    const double t = row->at("us_per_call").get<double>();
    EXPECT_TRUE(std::isfinite(t) && t > 0 && t < 1e5) << name << " = " << t;
    EXPECT_GT(number(*findRow(rows, std::string("build.") + name + ".total")), 0) << name;
    EXPECT_GT(number(*findRow(rows, std::string("build.") + name + ".compiler_peak_memory")), 0) << name;
    EXPECT_LT(j.at("checks").at(std::string("interpreter_vs_compiled_") + name).get<double>(), 1e-9) << name;
  }
  EXPECT_EQ(findRow(rows, "values_only_value"), nullptr);
  EXPECT_EQ(findRow(rows, "mass_matrix_value"), nullptr);
  // Values alone cost less than values with a 7 x 21 Jacobian and a gradient.
  EXPECT_LT(findRow(rows, "knot_value")->at("us_per_call").get<double>(),
            findRow(rows, "knot")->at("us_per_call").get<double>());
  EXPECT_NE(findRow(rows, "rnea_jacobian_dense"), nullptr);  // the built-in rows are still there
}

TEST(BenchCli, BadSpecsFailNamingTheProblem) {
  const fs::path urdf = testing::sourceDir() / "examples" / "robots" / "arm7.urdf";
  const ChainDir scratch(1);
  const fs::path taken = scratch.dir() / "taken.json", broken = scratch.dir() / "broken.json";
  std::ofstream(taken) << R"json({"name": "rnea_value", "inputs": {"q": "configuration"},
    "outputs": [{"name": "g", "kind": "value", "of": "gravity(q)"}]})json";
  std::ofstream(broken) << R"json({"inputs": {"q": "configuration"}, "outputs": [{"name": "g", "kind": "value", "of": "gravty(q)"}]})json";
  testing::ProcessResult r = runCommand(bench(urdf, "--quick --spec " + shellQuote(taken.string())));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("'rnea_value' is taken"), std::string::npos) << r.err;
  r = runCommand(bench(urdf, "--quick --spec " + shellQuote(broken.string())));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("gravty"), std::string::npos) << r.err;
  r = runCommand(bench(urdf, "--quick --spec /nonexistent/spec.json"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("spec.json"), std::string::npos) << r.err;
  const fs::path twice = scratch.dir() / "twice.json";
  std::ofstream(twice) << R"json({"name": "twice", "inputs": {"q": "configuration"},
    "outputs": [{"name": "g", "kind": "value", "of": "gravity(q)"}]})json";
  r = runCommand(bench(urdf, "--quick --spec " + shellQuote(twice.string()) + " --spec " + shellQuote(twice.string())));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("'twice' is taken"), std::string::npos) << r.err;
}

TEST(BenchCli, BadArgumentsFailWithAMessage) {
  const fs::path urdf = testing::sourceDir() / "examples" / "robots" / "arm7.urdf";
  testing::ProcessResult r = runCommand(shellQuote(cliPath().string()) + " bench --json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--urdf"), std::string::npos) << r.err;
  r = runCommand(bench("/nonexistent/robot.urdf", "--quick"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("robot.urdf"), std::string::npos) << r.err;
  r = runCommand(bench(urdf, "--json --markdown"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(r.out.empty()) << r.out;
}

}  // namespace
}  // namespace robodiff
