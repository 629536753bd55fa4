// CsvTable: one pass over the text splitting lines and fields into views; numbers are
// parsed with std::from_chars when asked for.
#include "robodiff/batch/csv_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>

#include "robodiff/batch/trajectory_error.hpp"

namespace robodiff::batch {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// A field as a person reads it in a message, in quotes: at most 40 characters.
std::string shown(std::string_view text) {
  std::string out = "'";
  out += text.size() <= 40 ? text : text.substr(0, 37);
  out += text.size() <= 40 ? "'" : "...'";
  return out;
}

// Splits one line into trimmed fields. A field in double quotes may hold commas ("" is a
// quote inside); its view keeps the quotes.
void splitFields(std::string_view line, std::vector<std::string_view>& out) {
  std::size_t start = 0;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) {
      out.push_back(trim(line.substr(start, i - start)));
      start = i + 1;
    }
  }
  out.push_back(trim(line.substr(start)));
}

// A header name without its quotes ("" inside becomes ").
std::string unquote(std::string_view field) {
  if (field.size() < 2 || field.front() != '"' || field.back() != '"') return std::string(field);
  std::string name;
  for (std::size_t i = 1; i + 1 < field.size(); ++i) {
    name += field[i];
    if (field[i] == '"' && field[i + 1] == '"') ++i;
  }
  return std::string(trim(name));
}

bool skipped(std::string_view line) {
  const std::string_view t = trim(line);
  return t.empty() || t.front() == '#';
}

}  // namespace

std::string locationOf(const std::string& source, std::size_t line) { return source + ":" + std::to_string(line) + ": "; }

std::optional<double> parseFiniteDouble(std::string_view text) {
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    if (!text.empty() && (text.front() == '+' || text.front() == '-')) return std::nullopt;  // "+-1"
  }
  if (text.empty()) return std::nullopt;
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

CsvTable CsvTable::parse(std::string text, const std::string& source) {
  CsvTable table;
  table.source_ = source;
  table.text_ = std::make_unique<const std::string>(std::move(text));
  const std::string_view all = *table.text_;

  std::vector<std::string_view> fields;
  std::size_t line_number = 0;
  for (std::size_t pos = 0; pos < all.size();) {
    std::size_t end = all.find('\n', pos);
    if (end == std::string_view::npos) end = all.size();
    const std::string_view line = all.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    if (skipped(line)) continue;
    fields.clear();
    splitFields(line, fields);
    if (table.header_.empty()) {
      table.header_line_ = line_number;
      std::set<std::string> seen;
      for (std::size_t c = 0; c < fields.size(); ++c) {
        std::string name = unquote(fields[c]);
        if (name.empty())
          throw TrajectoryError(locationOf(source, line_number) + "column " + std::to_string(c + 1) +
                                " of the header has no name");
        if (!seen.insert(name).second)
          throw TrajectoryError(locationOf(source, line_number) + "column '" + name + "' is named twice in the header");
        table.header_.push_back(std::move(name));
      }
      continue;
    }
    if (fields.size() != table.header_.size())
      throw TrajectoryError(locationOf(source, line_number) + std::to_string(fields.size()) + " field" +
                            (fields.size() == 1 ? "" : "s") + ", the header (line " +
                            std::to_string(table.header_line_) + ") has " + std::to_string(table.header_.size()));
    if (table.lines_.empty()) {  // room for every row, judged from the first one's length
      const std::size_t rows = all.size() / std::max<std::size_t>(line.size() + 1, 1) + 1;
      table.lines_.reserve(rows);
      table.fields_.reserve(rows * table.header_.size());
    }
    table.lines_.push_back(line_number);
    table.fields_.insert(table.fields_.end(), fields.begin(), fields.end());
  }
  if (table.header_.empty())
    throw TrajectoryError(source + ": no header row (the first line that is not blank or a # comment names the columns)");
  return table;
}

CsvTable CsvTable::readFile(const std::filesystem::path& path) { return parse(readWholeFile(path), path.string()); }

std::string readWholeFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw TrajectoryError(path.string() + ": cannot open the file");
  std::string text(static_cast<std::size_t>(in.tellg()), '\0');
  in.seekg(0);
  if (!in.read(text.data(), static_cast<std::streamsize>(text.size())))
    throw TrajectoryError(path.string() + ": cannot read the file");
  return text;
}

std::optional<std::size_t> CsvTable::column(std::string_view name) const {
  for (std::size_t c = 0; c < header_.size(); ++c)
    if (header_[c] == name) return c;
  return std::nullopt;
}

double CsvTable::number(std::size_t row, std::size_t col) const {
  const std::string_view text = field(row, col);
  if (const std::optional<double> value = parseFiniteDouble(text)) return *value;
  std::string what;
  if (text.empty()) {
    what = "is empty";
  } else {
    double value = 0;
    const bool plus = text.front() == '+' && text.size() > 1 && text[1] != '+' && text[1] != '-';
    const std::string_view digits = plus ? text.substr(1) : text;
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    const bool whole = end == digits.data() + digits.size();
    if (whole && error == std::errc::result_out_of_range)
      what = shown(text) + " is out of the range of a double";
    else
      what = shown(text) + " is " + (whole && error == std::errc() ? "not finite" : "not a number");
  }
  throw TrajectoryError(locationOf(source_, lines_[row]) + "column " + header_[col] + ": " + what);
}

}  // namespace robodiff::batch
