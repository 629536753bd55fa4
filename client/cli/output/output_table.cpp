#include "output/output_table.hpp"

#include <algorithm>
#include <cstdio>

namespace robodiff::cli {
namespace {

constexpr int kMaxColumns = 10;

std::string cellNumber(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

}  // namespace

Table Table::vector(const std::string& title, const std::vector<std::string>& labels, const Eigen::VectorXd& values) {
  Table t;
  t.rows_.push_back({"", title});
  for (Eigen::Index i = 0; i < values.size(); ++i)
    t.rows_.push_back({i < static_cast<Eigen::Index>(labels.size()) ? labels[i] : std::to_string(i), cellNumber(values[i])});
  return t;
}

Table Table::matrix(const std::string& title, const std::vector<std::string>& row_labels, const Eigen::MatrixXd& m,
                    const std::vector<std::string>& column_labels) {
  Table t;
  const Eigen::Index shown = std::min<Eigen::Index>(m.cols(), kMaxColumns);
  std::vector<std::string> header{title};
  for (Eigen::Index c = 0; c < shown; ++c)
    header.push_back(c < static_cast<Eigen::Index>(column_labels.size()) ? column_labels[c] : std::to_string(c));
  t.rows_.push_back(header);
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    std::vector<std::string> row{r < static_cast<Eigen::Index>(row_labels.size()) ? row_labels[r] : std::to_string(r)};
    for (Eigen::Index c = 0; c < shown; ++c) row.push_back(cellNumber(m(r, c)));
    t.rows_.push_back(row);
  }
  if (shown < m.cols())
    t.note_ = "(" + std::to_string(m.rows()) + " x " + std::to_string(m.cols()) + "; first " + std::to_string(shown) +
              " columns shown, --format json prints all)";
  return t;
}

Table Table::rows(const std::vector<std::string>& header, const std::vector<bool>& right_aligned) {
  Table t;
  t.rows_.push_back(header);
  t.right_aligned_ = right_aligned;
  t.right_aligned_.resize(header.size(), false);
  return t;
}

void Table::addRow(const std::vector<std::string>& row) { rows_.push_back(row); }

Table Table::placements() {
  Table t;
  t.rows_.push_back({"frame", "x", "y", "z", "R row 1", "", "", "R row 2", "", "", "R row 3", "", ""});
  return t;
}

void Table::addPlacement(const std::string& name, const Eigen::Vector3d& p, const Eigen::Matrix3d& R) {
  std::vector<std::string> row{name, cellNumber(p.x()), cellNumber(p.y()), cellNumber(p.z())};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) row.push_back(cellNumber(R(r, c)));
  rows_.push_back(row);
}

void Table::print(std::ostream& out) const {
  std::vector<size_t> width;
  for (const auto& row : rows_)
    for (size_t c = 0; c < row.size(); ++c) {
      if (width.size() <= c) width.push_back(0);
      width[c] = std::max(width[c], row[c].size());
    }
  for (size_t r = 0; r < rows_.size(); ++r) {
    std::string line;
    for (size_t c = 0; c < rows_[r].size(); ++c) {
      const std::string& cell = rows_[r][c];
      std::string pad(width[c] - cell.size(), ' ');
      const bool right = right_aligned_.empty() ? c > 0 : c < right_aligned_.size() && right_aligned_[c];
      line += (c == 0 ? "" : "  ") + (right ? pad + cell : cell + pad);  // labels left, numbers right
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out << line << "\n";
    if (r == 0) {
      size_t total = 0;
      for (size_t w : width) total += w + 2;
      out << std::string(total - 2, '-') << "\n";
    }
  }
  if (!note_.empty()) out << note_ << "\n";
}

}  // namespace robodiff::cli
