#include "robodiff/functions/evaluation.hpp"

namespace robodiff {

Eigen::MatrixXd blockMatrix(const codegen::OutputBlock& block, const Eigen::VectorXd& values, bool symmetric_lower) {
  if (values.size() != static_cast<Eigen::Index>(block.size()))
    throw std::invalid_argument("blockMatrix: block '" + block.name + "' has " + std::to_string(block.size()) +
                                " values, " + std::to_string(values.size()) + " given");
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(block.rows, block.cols);
  if (block.kind == codegen::OutputKind::Dense) {
    for (std::uint32_t r = 0, k = 0; r < block.rows; ++r)
      for (std::uint32_t c = 0; c < block.cols; ++c) m(r, c) = values[k++];
    return m;
  }
  for (std::uint32_t r = 0; r < block.rows; ++r)
    for (std::uint32_t k = block.row_ptr[r]; k < block.row_ptr[r + 1]; ++k) {
      m(r, block.col_idx[k]) = values[k];
      if (symmetric_lower) m(block.col_idx[k], r) = values[k];
    }
  return m;
}

}  // namespace robodiff
