// Measured samples: CSV reading (std::from_chars, no locale) and writing.
#include "robodiff/batch/measured_samples.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string_view>
#include <utility>

#include "robodiff/batch/identification_error.hpp"

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

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::string at(const std::string& source, std::size_t line) { return source + ":" + std::to_string(line) + ": "; }

// Splits one line on ',' into `fields` (trimmed views).
void split(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) return;
    start = comma + 1;
  }
}

// A field as a finite double, or a message saying why not.
bool parseNumber(std::string_view text, double& value, std::string& why) {
  if (text.empty()) return why = "is empty", false;
  std::string_view digits = text;
  if (digits.front() == '+') digits.remove_prefix(1);  // from_chars takes no '+'
  const char* end = digits.data() + digits.size();
  auto [ptr, ec] = std::from_chars(digits.data(), end, value, std::chars_format::general);
  if (digits.empty() || (digits.front() == '-' && text.front() == '+') || ec == std::errc::invalid_argument ||
      ptr != end)
    return why = "is not a number", false;
  if (ec == std::errc::result_out_of_range) return why = "is out of the range of a double", false;
  if (!std::isfinite(value)) return why = "is not finite", false;
  return true;
}

}  // namespace

std::vector<std::string> sampleColumns(const Model& model, bool with_time) {
  std::vector<std::string> out;
  if (with_time) out.push_back("t");
  for (auto& [name, target] : neededColumns(model)) out.push_back(name);
  return out;
}

MeasuredSamples parseMeasuredSamples(const std::string& text, const Model& model, const std::string& source) {
  MeasuredSamples samples;
  samples.source = source;
  const std::vector<std::pair<std::string, Target>> needed = neededColumns(model);

  std::vector<Target> targets;          // per header column; quantity -1: ignored
  std::vector<std::string> names;       // per header column
  std::size_t header_line = 0;
  std::vector<double> values;           // per sample: q, v, a, tau, t
  const std::size_t per_sample = static_cast<std::size_t>(model.nq + 3 * model.nv + 1);
  const int quantity_offset[] = {0, model.nq, model.nq + model.nv, model.nq + 2 * model.nv,
                                 model.nq + 3 * model.nv};
  bool has_time = false;
  std::vector<std::string_view> fields;
  std::string why;

  std::size_t line_number = 0, pos = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    std::string_view line(text.data() + pos, eol - pos);
    pos = eol + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::string_view content = trim(line);
    if (content.empty() || content.front() == '#') continue;
    split(line, fields);

    if (header_line == 0) {  // the header: map names to targets
      header_line = line_number;
      std::map<std::string, std::size_t> index;
      for (std::size_t c = 0; c < fields.size(); ++c) {
        std::string_view name = fields[c];
        if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
        if (name.empty())
          throw IdentificationError(at(source, line_number) + "column " + std::to_string(c + 1) +
                                    " of the header has no name");
        names.emplace_back(name);
        if (!index.emplace(std::string(name), c).second)
          throw IdentificationError(at(source, line_number) + "column " + std::string(name) +
                                    " appears twice in the header");
      }
      targets.assign(fields.size(), Target{});
      std::string missing;
      std::size_t missing_count = 0;
      for (const auto& [name, target] : needed) {
        auto it = index.find(name);
        if (it == index.end()) {
          missing += (missing.empty() ? "" : ", ") + name;
          ++missing_count;
          continue;
        }
        targets[it->second] = target;
        index.erase(it);
      }
      if (auto it = index.find("t"); it != index.end()) {
        targets[it->second] = {4, 0};
        has_time = true;
        index.erase(it);
      }
      if (missing_count > 0)
        throw IdentificationError(at(source, line_number) + "the header lacks " + std::to_string(missing_count) +
                                  (missing_count == 1 ? " column " : " columns ") + "of robot '" + model.name +
                                  "': " + missing + " (expected q_, v_, a_ and tau_ columns per joint)");
      for (const auto& [name, c] : index) samples.ignored_columns.push_back(name);
      continue;
    }

    if (fields.size() != targets.size())
      throw IdentificationError(at(source, line_number) + std::to_string(fields.size()) +
                                (fields.size() == 1 ? " field" : " fields") + ", the header has " +
                                std::to_string(targets.size()));
    const std::size_t base = values.size();
    values.resize(base + per_sample, 0.0);
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const Target& target = targets[c];
      if (target.quantity < 0) continue;  // an ignored column may hold anything
      double value = 0;
      if (!parseNumber(fields[c], value, why)) {
        throw IdentificationError(at(source, line_number) + "column " + names[c] + ": '" + std::string(fields[c]) +
                                  "' " + why);
      }
      values[base + static_cast<std::size_t>(quantity_offset[target.quantity] + target.row)] = value;
    }
    samples.lines.push_back(line_number);
  }
  if (header_line == 0) throw IdentificationError(source + ": no header row (the file has no data)");
  const std::size_t n = samples.lines.size();
  if (n == 0) throw IdentificationError(at(source, header_line) + "a header but no samples");

  Eigen::Map<const Eigen::MatrixXd> all(values.data(), static_cast<Eigen::Index>(per_sample),
                                        static_cast<Eigen::Index>(n));
  samples.q = all.topRows(model.nq);
  samples.v = all.middleRows(quantity_offset[1], model.nv);
  samples.a = all.middleRows(quantity_offset[2], model.nv);
  samples.tau = all.middleRows(quantity_offset[3], model.nv);
  if (has_time) samples.t = all.row(quantity_offset[4]).transpose();
  return samples;
}

MeasuredSamples readMeasuredSamples(const std::filesystem::path& path, const Model& model) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw IdentificationError(path.string() + ": cannot read samples: it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IdentificationError(path.string() + ": cannot open the samples file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw IdentificationError(path.string() + ": cannot read the samples file");
  return parseMeasuredSamples(text.str(), model, path.string());
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
