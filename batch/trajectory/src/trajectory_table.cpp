// Reading a trajectory: CSV or JSON columns mapped onto the function's input blocks.
#include "robodiff/batch/trajectory_table.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "robodiff/batch/csv_table.hpp"
#include "robodiff/batch/trajectory_error.hpp"
#include "robodiff/language/json_problem.hpp"

namespace robodiff::batch {
namespace {

using nlohmann::json;

constexpr double kQuaternionTolerance = 1e-5;
constexpr std::size_t kRowsPerThread = 8192;  // smaller files are parsed on one thread

// "a, b, c" for the first `limit` names, then "... (N in all)".
std::string listed(const std::vector<std::string>& names, std::size_t limit = 8) {
  std::string out;
  for (std::size_t i = 0; i < names.size() && i < limit; ++i) out += (i ? ", " : "") + names[i];
  if (names.size() > limit) out += ", ... (" + std::to_string(names.size()) + " in all)";
  return out;
}

// The floating bases' quaternions: offsets (in block q) of qx, the three others follow.
std::vector<std::size_t> quaternionOffsets(const Model& model) {
  std::vector<std::size_t> offsets;
  for (const Joint& j : model.joints)
    if (j.type == JointType::FreeFlyer) offsets.push_back(static_cast<std::size_t>(j.idx_q) + 3);
  return offsets;
}

// Whether `block` is a configuration of the model: named in `configurations`, nq entries.
bool isConfiguration(const Model& model, const BlockLayout& block, const std::vector<std::string>& configurations) {
  return block.size == static_cast<std::uint32_t>(model.nq) &&
         std::find(configurations.begin(), configurations.end(), block.name) != configurations.end();
}

// The norm of each quaternion in the configuration blocks of one knot, checked; `where`
// names the knot.
void checkQuaternions(const Model& model, const std::vector<BlockLayout>& inputs,
                      const std::vector<std::string>& configurations, const double* knot,
                      const std::vector<std::vector<std::string>>& block_columns, const std::string& where) {
  for (std::size_t b = 0; b < inputs.size(); ++b) {
    if (!isConfiguration(model, inputs[b], configurations)) continue;
    for (std::size_t at : quaternionOffsets(model)) {
      const double* quat = knot + inputs[b].offset + at;
      const double norm = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
      if (std::abs(norm - 1.0) > kQuaternionTolerance) {
        std::ostringstream message;
        message.precision(9);
        message << where << "columns " << block_columns[b][at] << " .. " << block_columns[b][at + 3]
                << ": the quaternion has norm " << norm << ", not 1";
        throw TrajectoryError(message.str());
      }
    }
  }
}

// Coordinate k of a joint: "elbow", "root_qw", "ball_2".
std::string coordinateName(const Joint& joint, int k, bool configuration) {
  static const char* kConfiguration[] = {"x", "y", "z", "qx", "qy", "qz", "qw"};
  static const char* kTangent[] = {"vx", "vy", "vz", "wx", "wy", "wz"};
  const int count = configuration ? joint.nq : joint.nv;
  if (count == 1) return joint.name;
  if (joint.type == JointType::FreeFlyer) return joint.name + "_" + (configuration ? kConfiguration[k] : kTangent[k]);
  return joint.name + "_" + std::to_string(k);
}

std::string suffixedName(const std::string& block, const Joint& joint, int k, bool configuration) {
  return block + "_" + coordinateName(joint, k, configuration);
}

// Where each input block's entries come from in the CSV header, or an error naming what is missing.
std::vector<std::vector<std::size_t>> mapColumns(const CsvTable& csv, const Model& model,
                                                 const std::vector<BlockLayout>& inputs,
                                                 const std::vector<std::string>& configurations,
                                                 std::vector<std::vector<std::string>>& block_columns) {
  std::vector<std::vector<std::size_t>> columns;
  for (const BlockLayout& block : inputs) {
    const std::vector<std::string> named = jointColumns(model, block, configurations);
    const std::vector<std::string> indexed = indexColumns(block);
    auto present = [&](const std::vector<std::string>& names) {
      std::size_t n = 0;
      for (const std::string& name : names) n += csv.column(name).has_value();
      return n;
    };
    const std::size_t named_found = present(named), indexed_found = present(indexed);
    const std::vector<std::string>* chosen = nullptr;
    if (!named.empty() && named_found == named.size())
      chosen = &named;
    else if (indexed_found == indexed.size())
      chosen = &indexed;
    if (!chosen) {
      const std::vector<std::string>& closer = !named.empty() && named_found >= indexed_found ? named : indexed;
      std::vector<std::string> missing;
      for (const std::string& name : closer)
        if (!csv.column(name)) missing.push_back(name);
      std::string expected = named.empty() ? "" : named.front() + " .. " + named.back() + " (by joint) or ";
      expected += indexed.front() + " .. " + indexed.back() + " (by index)";
      throw TrajectoryError(locationOf(csv.source(), csv.headerLine()) + "input block '" + block.name + "' (" +
                            std::to_string(block.size) + " entries) needs the columns " + expected + "; missing: " +
                            listed(missing));
    }
    std::vector<std::size_t> cols;
    for (const std::string& name : *chosen) cols.push_back(*csv.column(name));
    columns.push_back(std::move(cols));
    block_columns.push_back(*chosen);
  }
  return columns;
}

// "[k]" as JSON paths name an array entry.
std::string indexText(std::size_t k) {
  std::string text = "[";
  text += std::to_string(k);
  text += ']';
  return text;
}

// A JSON number as a finite double; `path` names it in the message.
double jsonNumber(const json& value, const std::string& source, const std::string& path) {
  if (!value.is_number()) throw TrajectoryError(source + ": " + path + ": " + value.dump() + " is not a number");
  const double x = value.get<double>();
  if (!std::isfinite(x)) throw TrajectoryError(source + ": " + path + ": " + value.dump() + " is not finite");
  return x;
}

void readJsonBlock(const json& value, const BlockLayout& block, const std::string& source, const std::string& path,
                   double* out) {
  if (!value.is_array() || value.size() != block.size)
    throw TrajectoryError(source + ": " + path + ": " +
                          (value.is_array() ? std::to_string(value.size()) + " entries" : "not an array") +
                          ", input block '" + block.name + "' has " + std::to_string(block.size));
  for (std::size_t i = 0; i < block.size; ++i)
    out[i] = jsonNumber(value[i], source, path + "[" + std::to_string(i) + "]");
}

}  // namespace

std::vector<std::string> configurationInputs(const FunctionSpec& spec) {
  if (!spec.isUser()) return {"q"};
  std::vector<std::string> names;
  for (const UserInput& in : spec.user->inputs)
    if (in.kind == UserInput::Kind::Configuration) names.push_back(in.name);
  return names;
}

std::vector<std::string> jointColumns(const Model& model, const BlockLayout& block,
                                      const std::vector<std::string>& configurations) {
  std::vector<std::string> names;
  const bool configuration = isConfiguration(model, block, configurations);
  const bool tangent = !configuration && block.size == static_cast<std::uint32_t>(model.nv);
  if (!configuration && !tangent) return names;
  for (const Joint& joint : model.joints)
    for (int k = 0; k < (configuration ? joint.nq : joint.nv); ++k)
      names.push_back(suffixedName(block.name, joint, k, configuration));
  return names;
}

std::vector<std::string> dofNames(const Model& model) {
  std::vector<std::string> names;
  for (const Joint& joint : model.joints)
    for (int k = 0; k < joint.nv; ++k) names.push_back(coordinateName(joint, k, false));
  return names;
}

std::vector<std::string> indexColumns(const BlockLayout& block) {
  std::vector<std::string> names;
  for (std::uint32_t i = 0; i < block.size; ++i) names.push_back(block.name + "_" + std::to_string(i));
  return names;
}

TrajectoryTable parseTrajectoryCsv(std::string text, const std::string& source, const Model& model,
                                   const std::vector<BlockLayout>& inputs,
                                   const std::vector<std::string>& configurations) {
  const CsvTable csv = CsvTable::parse(std::move(text), source);
  TrajectoryTable table;
  table.source = source;
  const std::vector<std::vector<std::size_t>> columns =
      mapColumns(csv, model, inputs, configurations, table.block_columns);
  std::optional<std::size_t> time_column = csv.column("t");
  if (!time_column) time_column = csv.column("time");

  std::vector<bool> used(csv.columns(), false);
  if (time_column) used[*time_column] = true;
  for (const auto& cols : columns)
    for (std::size_t c : cols) used[c] = true;
  for (std::size_t c = 0; c < csv.columns(); ++c)
    if (!used[c]) table.ignored_columns.push_back(csv.header()[c]);

  for (const BlockLayout& block : inputs) table.input_count = std::max<std::size_t>(table.input_count, block.offset + block.size);
  table.knots = csv.rows();
  table.inputs.resize(table.knots * table.input_count);
  table.lines.resize(table.knots);
  if (time_column) table.times.resize(table.knots);
  const bool has_quaternion = !quaternionOffsets(model).empty();
  // Rows [begin, end) into the table; the numbers are parsed on all cores.
  auto parseRows = [&](std::size_t begin, std::size_t end) {
    for (std::size_t row = begin; row < end; ++row) {
      double* knot = table.inputs.data() + row * table.input_count;
      table.lines[row] = csv.lineOf(row);
      if (time_column) table.times[row] = csv.number(row, *time_column);
      for (std::size_t b = 0; b < inputs.size(); ++b)
        for (std::size_t i = 0; i < columns[b].size(); ++i) knot[inputs[b].offset + i] = csv.number(row, columns[b][i]);
      if (has_quaternion)
        checkQuaternions(model, inputs, configurations, knot, table.block_columns, locationOf(source, csv.lineOf(row)));
    }
  };
  const std::size_t threads = std::clamp<std::size_t>(csv.rows() / kRowsPerThread, 1, std::max(1u, std::thread::hardware_concurrency()));
  std::vector<std::exception_ptr> errors(threads);  // each thread's first; the earliest row's is thrown
  std::vector<std::thread> pool;
  auto slice = [&](std::size_t t) {
    try {
      parseRows(csv.rows() * t / threads, csv.rows() * (t + 1) / threads);
    } catch (...) {
      errors[t] = std::current_exception();
    }
  };
  for (std::size_t t = 1; t < threads; ++t) pool.emplace_back(slice, t);
  slice(0);
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& error : errors)
    if (error) std::rethrow_exception(error);
  return table;
}

TrajectoryTable parseTrajectoryJson(const std::string& text, const std::string& source, const Model& model,
                                    const std::vector<BlockLayout>& inputs,
                                    const std::vector<std::string>& configurations) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    // The line of the byte where parsing stopped.
    const std::size_t byte = std::min<std::size_t>(e.byte, text.size());
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + byte, '\n'));
    throw TrajectoryError(locationOf(source, line) + "not valid JSON: " + language::jsonProblem(e.what()));
  }
  TrajectoryTable table;
  table.source = source;
  for (const BlockLayout& block : inputs) {
    table.input_count = std::max<std::size_t>(table.input_count, block.offset + block.size);
    std::vector<std::string> entries;  // as quaternion messages name them
    for (std::uint32_t i = 0; i < block.size; ++i) entries.push_back(block.name + "[" + std::to_string(i) + "]");
    table.block_columns.push_back(std::move(entries));
  }
  std::set<std::string> used = {"t", "time"};
  for (const BlockLayout& block : inputs) used.insert(block.name);
  auto timeKey = [](const json& object) -> const char* {
    return object.contains("t") ? "t" : object.contains("time") ? "time" : nullptr;
  };

  if (root.is_object()) {
    // Block-major: every block an array with one entry per knot.
    std::optional<std::size_t> knots;
    std::string knots_from;
    auto sized = [&](const std::string& key) -> const json& {
      const json& value = root[key];
      if (!value.is_array()) throw TrajectoryError(source + ": " + key + ": not an array (one entry per knot)");
      if (knots && value.size() != *knots)
        throw TrajectoryError(source + ": " + key + ": " + std::to_string(value.size()) + " knots, " + knots_from +
                              " has " + std::to_string(*knots));
      if (!knots) knots = value.size(), knots_from = key;
      return value;
    };
    for (const BlockLayout& block : inputs)
      if (!root.contains(block.name))
        throw TrajectoryError(source + ": no \"" + block.name + "\": input block '" + block.name + "' needs an array of " +
                              std::to_string(block.size) + " numbers per knot");
    const char* time_key = timeKey(root);
    const json* times = time_key ? &sized(time_key) : nullptr;
    std::vector<const json*> blocks;
    for (const BlockLayout& block : inputs) blocks.push_back(&sized(block.name));
    table.knots = knots.value_or(0);
    table.inputs.resize(table.knots * table.input_count);
    if (times) table.times.resize(table.knots);
    for (std::size_t k = 0; k < table.knots; ++k) {
      const std::string index = indexText(k);
      if (times) table.times[k] = jsonNumber((*times)[k], source, std::string(time_key) + index);
      double* knot = table.inputs.data() + k * table.input_count;
      for (std::size_t b = 0; b < inputs.size(); ++b)
        readJsonBlock((*blocks[b])[k], inputs[b], source, inputs[b].name + index, knot + inputs[b].offset);
      checkQuaternions(model, inputs, configurations, knot, table.block_columns,
                       source + ": knot " + std::to_string(k) + ": ");
    }
    for (const auto& [key, value] : root.items())
      if (!used.count(key)) table.ignored_columns.push_back(key);
  } else if (root.is_array()) {
    // Knot-major: one object per knot.
    table.knots = root.size();
    table.inputs.resize(table.knots * table.input_count);
    std::set<std::string> ignored;
    const char* first_time_key = root.empty() || !root[0].is_object() ? nullptr : timeKey(root[0]);
    if (first_time_key) table.times.resize(table.knots);
    for (std::size_t k = 0; k < table.knots; ++k) {
      const std::string at = indexText(k);
      const json& object = root[k];
      if (!object.is_object()) throw TrajectoryError(source + ": " + at + ": not an object {\"q\": [...], ...}");
      double* knot = table.inputs.data() + k * table.input_count;
      for (const BlockLayout& block : inputs) {
        if (!object.contains(block.name))
          throw TrajectoryError(source + ": " + at + ": no \"" + block.name + "\" (input block '" + block.name +
                                "', " + std::to_string(block.size) + " numbers)");
        readJsonBlock(object[block.name], block, source, at + "." + block.name, knot + block.offset);
      }
      if (first_time_key) {
        const char* key = timeKey(object);
        if (!key) throw TrajectoryError(source + ": " + at + ": no \"t\" (knot 0 has one; every knot needs it then)");
        table.times[k] = jsonNumber(object[key], source, at + "." + key);
      }
      checkQuaternions(model, inputs, configurations, knot, table.block_columns,
                       source + ": knot " + std::to_string(k) + ": ");
      for (const auto& [key, value] : object.items())
        if (!used.count(key)) ignored.insert(key);
    }
    table.ignored_columns.assign(ignored.begin(), ignored.end());
  } else {
    throw TrajectoryError(source + ": the trajectory must be an object {\"t\": [...], \"q\": [[...], ...], ...} or an "
                          "array of knots [{\"t\": ..., \"q\": [...], ...}, ...]");
  }
  return table;
}

TrajectoryTable readTrajectoryFile(const std::filesystem::path& path, const Model& model,
                                   const std::vector<BlockLayout>& inputs,
                                   const std::vector<std::string>& configurations) {
  std::string text = readWholeFile(path);
  if (path.extension() == ".json") return parseTrajectoryJson(text, path.string(), model, inputs, configurations);
  return parseTrajectoryCsv(std::move(text), path.string(), model, inputs, configurations);
}

}  // namespace robodiff::batch
