// A JSON array (of numbers: a vector; of arrays: a row-major matrix) as an Eigen
// matrix, for comparing the CLI's JSON output with the library.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace robodiff::testing {

inline Eigen::MatrixXd matrixOf(const nlohmann::json& j) {
  if (!j.is_array() || j.empty()) return {};
  if (!j[0].is_array()) {
    Eigen::VectorXd v(j.size());
    for (size_t i = 0; i < j.size(); ++i) v[i] = j[i].get<double>();
    return v;
  }
  Eigen::MatrixXd m(j.size(), j[0].size());
  for (size_t r = 0; r < j.size(); ++r)
    for (size_t c = 0; c < j[r].size(); ++c) m(r, c) = j[r][c].get<double>();
  return m;
}

}  // namespace robodiff::testing
