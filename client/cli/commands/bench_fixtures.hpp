// What `robodiff bench` (bench_command.cpp) measures with: the functions it builds, their
// input and output buffers, the finite-difference reference, the figures of other projects
// for the robots of ../shared/notes/anchors.md, and facts about the machine.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bench_timing.hpp"
#include "output/bench_report.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/dynamics/all.hpp"
#include "robodiff/functions/function_library.hpp"

namespace robodiff::cli::bench {

constexpr std::uint64_t kKnots = 1000;
constexpr std::uint64_t kSeed = 1;
constexpr double kFiniteDifferenceStep = 1e-6;

// Where the libraries are built: a temporary directory (removed), or `keep` (kept).
class WorkDir {
 public:
  explicit WorkDir(const std::string& keep);
  ~WorkDir();
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  bool remove_ = false;
};

// Figures of other projects and the targets, by row name.
struct Anchors {
  std::map<std::string, std::string> text;  // row name -> figures of other projects
  std::map<std::string, Target> targets;    // row name -> target on the value
};
// ../shared/notes/anchors.md's figures for Panda, Talos (fixed base) and UR5; none for others.
std::optional<Anchors> anchorsFor(const Model& model);

std::string cpuModel();
unsigned hardwareThreads();
std::uint64_t processPeakBytes();
std::string today();

// The functions benchmarked: name, label and spec.
struct SpecText {
  const char* name;
  const char* label;
  const char* json;
};
extern const std::vector<SpecText> kSpecs;
// The spec with the build every bench function uses (O2, -march=native).
std::string withBuild(const char* json);

// A function `robodiff bench` builds and times: its row name (also the C name), label,
// spec text, and where the spec came from (for errors).
struct BenchSpec {
  std::string name, label, json, source;
};
// The built-in rows (kSpecs, each with withBuild).
std::vector<BenchSpec> builtinBenchSpecs();
// `--spec FILE`, each: the whole spec as row NAME (the spec's "name", else the file's
// stem made an identifier) and, when it has outputs besides values, its value outputs
// alone as row NAME_value. Its own build options are kept (the defaults are the same as
// the built-in rows'). Throws std::invalid_argument naming the file for a spec that does
// not parse, or a row name that is in `taken` or given twice.
std::vector<BenchSpec> userBenchSpecs(const std::vector<std::string>& paths, std::vector<std::string> taken);

struct Generated {
  std::string name, label;
  FunctionSpec spec;
  GeneratedFunctionLibrary lib;
  double total_seconds = 0;
  std::uint64_t process_peak_bytes = 0;
  bool reused = false;  // loaded from an earlier run's --keep DIR: no build measured
  // The library loaded from `copies` files (the built one first): identical bytes on
  // other pages, because where a library's pages land moves its speed by up to 2x.
  std::vector<codegen::CompiledFunction> copies;
  const codegen::CompiledFunction& fn() const { return copies.front(); }
};

// Median of one timing per copy of the library (`time` returns seconds).
template <class Time> double medianOverCopies(const Generated& g, Time&& time) {
  std::vector<double> t;
  for (const codegen::CompiledFunction& f : g.copies) t.push_back(time(f));
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

// Input and output buffers of `knots` knots (knot-major per block, abi.h) and a work
// buffer, each on a 64-byte boundary; inputs drawn with seeds kSeed + knot.
struct Buffers {
  std::vector<AlignedDoubles> in, out;
  std::vector<std::uint32_t> in_size, out_size;
  std::vector<const double*> in_ptr;
  std::vector<double*> out_ptr;
  AlignedDoubles work;

  Buffers(const Model& model, const Generated& g, std::uint64_t knots, std::size_t work_size);
  Eigen::VectorXd input(std::size_t block, std::uint64_t knot = 0) const;
  Eigen::VectorXd output(std::size_t block, std::uint64_t knot = 0) const;
};

// Central differences of double RNEA over [q, v, a]: 2 * 3nv RNEA calls and the
// differencing, into J (nv x 3nv, q columns in the tangent space).
class RneaFiniteDifferences {
 public:
  RneaFiniteDifferences(const Model& model, Eigen::VectorXd q, Eigen::VectorXd v, Eigen::VectorXd a);
  void operator()();
  const Eigen::MatrixXd& jacobian() const { return J_; }

 private:
  void column(Eigen::VectorXd& x, int i, int col);

  const Model& model_;
  Data<double> data_;
  Eigen::VectorXd q_, v_, a_, plus_, dq_;
  Eigen::MatrixXd J_;
};

// max |actual - expected| / max(1, max |expected|).
double relativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected);

Row makeRow(std::string name, std::string label, std::string short_label, Unit unit, double value,
            std::vector<Ratio> ratios = {});

}  // namespace robodiff::cli::bench
