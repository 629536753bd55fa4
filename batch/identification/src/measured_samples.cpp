// Measured samples: reading through batch/trajectory's CsvTable (the project's CSV
// dialect and its messages), and writing.
#include "robodiff/batch/measured_samples.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <utility>

#include "robodiff/batch/csv_table.hpp"
#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/trajectory_error.hpp"

namespace robodiff::batch {
namespace {

const char* const kFreeFlyerQ[] = {".x", ".y", ".z", ".qx", ".qy", ".qz", ".qw"};
const char* const kFreeFlyerV[] = {".vx", ".vy", ".vz", ".wx", ".wy", ".wz"};

// Where a needed column goes: which quantity (0 q, 1 v, 2 a, 3 tau, 4 t) and which row.
struct Target {
  int quantity = -1;
  int row = 0;
};

std::vector<std::pair<std::string, Target>> neededColumns(const Model& model) {
  std::vector<std::pair<std::string, Target>> out;
  const char* prefixes[] = {"q_", "v_", "a_", "tau_"};
  for (int quantity = 0; quantity < 4; ++quantity)
    for (const Joint& j : model.joints) {
      const int n = quantity == 0 ? j.nq : j.nv;
      const int start = quantity == 0 ? j.idx_q : j.idx_v;
      for (int k = 0; k < n; ++k) {
        std::string name = prefixes[quantity] + j.name;
        if (j.type == JointType::FreeFlyer) name += quantity == 0 ? kFreeFlyerQ[k] : kFreeFlyerV[k];
        else if (n > 1) name += "." + std::to_string(k);
        out.push_back({std::move(name), {quantity, start + k}});
      }
    }
  return out;
}

// The samples of a parsed table: the needed columns found by name, every field of theirs
// a finite number (CsvTable::number's TrajectoryError otherwise, turned into an
// IdentificationError by the callers).
MeasuredSamples samplesOf(const CsvTable& table, const Model& model) {
  MeasuredSamples samples;
  samples.source = table.source();
  const std::string& source = table.source();
  const std::size_t header_line = table.headerLine();

  // Each needed column's place in the table; missing ones listed together.
  std::vector<std::pair<std::size_t, Target>> used;  // (table column, target)
  std::vector<bool> is_used(table.columns(), false);
  std::string missing;
  std::size_t missing_count = 0;
  for (const auto& [name, target] : neededColumns(model)) {
    const std::optional<std::size_t> c = table.column(name);
    if (!c) {
      missing += (missing.empty() ? "" : ", ") + name;
      ++missing_count;
      continue;
    }
    used.push_back({*c, target});
    is_used[*c] = true;
  }
  const std::optional<std::size_t> time = table.column("t");
  if (time) {
    used.push_back({*time, {4, 0}});
    is_used[*time] = true;
  }
  std::sort(used.begin(), used.end(), [](const auto& x, const auto& y) { return x.first < y.first; });  // file order
  if (missing_count > 0)
    throw IdentificationError(locationOf(source, header_line) + "the header lacks " + std::to_string(missing_count) +
                              (missing_count == 1 ? " column " : " columns ") + "of robot '" + model.name + "': " +
                              missing + " (expected q_, v_, a_ and tau_ columns per joint)");
  for (std::size_t c = 0; c < table.columns(); ++c)
    if (!is_used[c]) samples.ignored_columns.push_back(table.header()[c]);
  std::sort(samples.ignored_columns.begin(), samples.ignored_columns.end());

  const std::size_t n = table.rows();
  if (n == 0) throw IdentificationError(locationOf(source, header_line) + "a header but no samples");
  // Column k of `all` is sample k: q, v, a, tau, t.
  const int offset[] = {0, model.nq, model.nq + model.nv, model.nq + 2 * model.nv, model.nq + 3 * model.nv};
  Eigen::MatrixXd all(offset[4] + 1, static_cast<Eigen::Index>(n));
  all.setZero();
  samples.lines.resize(n);
  for (std::size_t row = 0; row < n; ++row) {
    for (const auto& [c, target] : used)
      all(offset[target.quantity] + target.row, static_cast<Eigen::Index>(row)) = table.number(row, c);
    samples.lines[row] = table.lineOf(row);
  }
  samples.q = all.topRows(model.nq);
  samples.v = all.middleRows(offset[1], model.nv);
  samples.a = all.middleRows(offset[2], model.nv);
  samples.tau = all.middleRows(offset[3], model.nv);
  if (time) samples.t = all.row(offset[4]).transpose();
  return samples;
}

}  // namespace

std::vector<std::string> sampleColumns(const Model& model, bool with_time) {
  std::vector<std::string> out;
  if (with_time) out.push_back("t");
  for (auto& [name, target] : neededColumns(model)) out.push_back(name);
  return out;
}

MeasuredSamples parseMeasuredSamples(const std::string& text, const Model& model, const std::string& source) {
  try {
    return samplesOf(CsvTable::parse(text, source), model);
  } catch (const TrajectoryError& e) {  // the table's errors, as this layer's
    throw IdentificationError(e.what());
  }
}

MeasuredSamples readMeasuredSamples(const std::filesystem::path& path, const Model& model) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw IdentificationError(path.string() + ": cannot read samples: it is a directory");
  try {
    return samplesOf(CsvTable::readFile(path), model);
  } catch (const TrajectoryError& e) {
    throw IdentificationError(e.what());
  }
}

std::string formatMeasuredSamples(const MeasuredSamples& samples, const Model& model) {
  const std::vector<std::string> columns = sampleColumns(model, samples.t.has_value());
  std::string out;
  for (std::size_t c = 0; c < columns.size(); ++c) out += (c ? "," : "") + columns[c];
  out += "\n";
  char buffer[32];
  auto put = [&](double x, bool first) {
    const int n = std::snprintf(buffer, sizeof buffer, "%.17g", x);
    if (!first) out += ',';
    out.append(buffer, static_cast<std::size_t>(n));
  };
  for (Eigen::Index k = 0; k < samples.q.cols(); ++k) {
    bool first = true;
    if (samples.t) put((*samples.t)[k], std::exchange(first, false));
    for (const Eigen::MatrixXd* m : {&samples.q, &samples.v, &samples.a, &samples.tau})
      for (Eigen::Index r = 0; r < m->rows(); ++r) put((*m)(r, k), std::exchange(first, false));
    out += '\n';
  }
  return out;
}

void writeMeasuredSamples(const std::filesystem::path& path, const MeasuredSamples& samples, const Model& model) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw IdentificationError(path.string() + ": cannot write the samples file");
  out << formatMeasuredSamples(samples, model);
  if (!out) throw IdentificationError(path.string() + ": writing the samples file failed");
}

MeasuredSamples sliceSamples(const MeasuredSamples& samples, std::size_t begin, std::size_t end) {
  MeasuredSamples out;
  out.source = samples.source;
  const auto b = static_cast<Eigen::Index>(begin), n = static_cast<Eigen::Index>(end - begin);
  out.q = samples.q.middleCols(b, n);
  out.v = samples.v.middleCols(b, n);
  out.a = samples.a.middleCols(b, n);
  out.tau = samples.tau.middleCols(b, n);
  if (samples.t) out.t = samples.t->segment(b, n);
  if (samples.lines.size() >= end) out.lines.assign(samples.lines.begin() + b, samples.lines.begin() + b + n);
  out.ignored_columns = samples.ignored_columns;
  return out;
}

}  // namespace robodiff::batch
