// The result of `robodiff bench` for one robot: rows (a time per call, a duration, a
// size or a count), their ratios to other rows of the same run, targets with PASS/MISS,
// and figures of other projects to compare with; printed as aligned text, as markdown
// for docs/benchmarks.md, or as JSON.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace robodiff::cli::bench {

enum class Unit { Microseconds, Seconds, Bytes, Count };

struct Ratio {
  std::string to;  // the name of the row divided by
  double value = 0;
};

// Met when the row's value (or, with ratio_to, its ratio to that row) is <= limit.
struct Target {
  double limit = 0;
  std::string ratio_to;  // empty: the value itself
  std::string text;      // how a reader sees it, e.g. "<= 0.9 µs"
};

struct Row {
  std::string name;         // stable identifier (JSON "name")
  std::string label;        // what a reader sees
  std::string short_label;  // how other rows' ratios name it; empty: the label
  Unit unit = Unit::Microseconds;
  double value = 0;
  std::vector<Ratio> ratios;
  std::optional<Target> target;
  std::string anchor;  // a figure of another project on this machine kind, in words
  std::string group;   // generation rows: the function they belong to
  std::string field;   // generation rows: trace, differentiate, ... (a column)

  // "" without a target, else "PASS" or "MISS".
  std::string status() const;
  const Ratio* ratio(const std::string& to) const;
};

struct Report {
  std::string robot, urdf;
  bool floating_base = false;
  int nq = 0, nv = 0;
  std::string machine;        // CPU and threads
  std::string code_flags;     // compiler and flags of the generated code
  std::string timing;         // how times were taken
  std::string anchor_source;  // where the anchor figures come from; empty: none for this robot
  std::vector<Row> evaluation;
  std::vector<Row> generation;
  std::vector<std::string> generation_functions;  // groups of `generation`, in order
  nlohmann::json checks = nlohmann::json::object();

  void printText(std::ostream& out) const;
  void printMarkdown(std::ostream& out) const;
  nlohmann::json toJson() const;
};

}  // namespace robodiff::cli::bench
