// Readable fixed-width tables for terminal output of the CLI.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace robodiff::cli {

class Table {
 public:
  // One value per labelled row.
  static Table vector(const std::string& title, const std::vector<std::string>& labels, const Eigen::VectorXd& values);
  // A matrix with labelled rows (and columns: indices when none are given). Wide
  // matrices show their first columns and say how many are left out.
  static Table matrix(const std::string& title, const std::vector<std::string>& row_labels, const Eigen::MatrixXd& m,
                      const std::vector<std::string>& column_labels = {});
  // Free-form rows under a header: text left-aligned, except the columns marked in
  // `right_aligned` (numbers).
  static Table rows(const std::vector<std::string>& header, const std::vector<bool>& right_aligned = {});
  void addRow(const std::vector<std::string>& row);
  // Frame placements: name, translation, rotation rows.
  static Table placements();
  void addPlacement(const std::string& name, const Eigen::Vector3d& p, const Eigen::Matrix3d& R);

  void print(std::ostream& out) const;

 private:
  std::vector<std::vector<std::string>> rows_;  // rows_[0] is the header
  // Per column; empty: the first column left-aligned (labels), the others right (numbers).
  std::vector<bool> right_aligned_;
  std::string note_;
};

}  // namespace robodiff::cli
