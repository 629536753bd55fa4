#pragma once
// A numeric CSV file held in memory: a header row naming the columns, then one row per
// record, fields kept as views into the text and parsed to doubles on demand (so that
// columns nobody uses may hold anything).
//
// Accepted: ',' separators; '\n' or "\r\n" line ends; blank lines and lines starting with
// '#' (comments) anywhere, skipped; spaces and tabs around fields; header names in double
// quotes. Line numbers are the file's physical lines, 1-based (the header is line 1 when
// nothing precedes it). Every row must have as many fields as the header.

#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace robodiff::batch {

class CsvTable {
 public:
  // Throws TrajectoryError naming `source` and the line: no header, an empty or repeated
  // column name, a row whose width differs from the header's.
  static CsvTable parse(std::string text, const std::string& source);
  static CsvTable readFile(const std::filesystem::path& path);  // the message names the path

  const std::string& source() const { return source_; }
  const std::vector<std::string>& header() const { return header_; }
  std::size_t headerLine() const { return header_line_; }
  std::size_t rows() const { return lines_.size(); }
  std::size_t columns() const { return header_.size(); }
  std::size_t lineOf(std::size_t row) const { return lines_[row]; }
  std::optional<std::size_t> column(std::string_view name) const;

  std::string_view field(std::size_t row, std::size_t col) const { return fields_[row * header_.size() + col]; }
  // The field as a finite double; throws TrajectoryError "source:line: column NAME: 'text' is
  // not a number" (or "is not finite", "is empty").
  double number(std::size_t row, std::size_t col) const;

 private:
  std::string source_;
  std::unique_ptr<const std::string> text_;  // fields_ point into it; its address survives moves
  std::vector<std::string> header_;
  std::size_t header_line_ = 0;
  std::vector<std::size_t> lines_;           // per row
  std::vector<std::string_view> fields_;     // row-major, rows() x columns()
};

// A finite double from the whole of `text` (spaces around it already trimmed); nullopt when
// it is not one. Accepts what strtod does for decimal numbers, a leading '+' included.
std::optional<double> parseFiniteDouble(std::string_view text);

// The whole file as bytes; throws TrajectoryError naming the path.
std::string readWholeFile(const std::filesystem::path& path);

// "file:line: " as messages start.
std::string locationOf(const std::string& source, std::size_t line);

}  // namespace robodiff::batch
