#include "service/service_helpers.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace robodiff::cli {

std::string readTextFile(const std::string& path, const std::string& option) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(option + " " + path + ": cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

rpc::LoadModelReply loadModelOnServer(const ServiceConnection& c, const std::string& urdf_text, bool floating_base) {
  rpc::LoadModelRequest request;
  request.urdf = urdf_text;
  request.floating_base = floating_base;
  rpc::LoadModelReply reply;
  check(c->loadModel(request, reply, c.call()), "LoadModel");
  return reply;
}

rpc::GetFunctionReply getFunctionOnServer(const ServiceConnection& c, const std::string& model_id,
                                          const std::string& spec_json, bool wait) {
  rpc::GetFunctionRequest request;
  request.model_id = model_id;
  request.spec_json = spec_json;
  request.wait = wait;
  rpc::GetFunctionReply reply;
  check(c->getFunction(request, reply, c.call()), "GetFunction");
  return reply;
}

Eigen::MatrixXd blockMatrix(const rpc::OutputBlock& block, std::span<const double> values) {
  if (values.size() != block.nnz)
    throw std::runtime_error("output block " + block.name + ": " + std::to_string(values.size()) +
                             " values for " + std::to_string(block.nnz));
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(block.rows, block.cols);
  if (block.layout == rpc::OutputLayout::DenseRowMajor) {
    for (std::uint32_t r = 0, k = 0; r < block.rows; ++r)
      for (std::uint32_t c = 0; c < block.cols; ++c) m(r, c) = values[k++];
    return m;
  }
  if (block.row_offsets.size() != block.rows + 1u || block.col_indices.size() != block.nnz)
    throw std::runtime_error("output block " + block.name + ": a malformed sparsity pattern from the server");
  const bool mirror = block.kind == rpc::OutputKind::Hessian;
  for (std::uint32_t r = 0; r < block.rows; ++r)
    for (std::uint32_t k = block.row_offsets[r]; k < block.row_offsets[r + 1] && k < block.nnz; ++k) {
      const std::uint32_t c = block.col_indices[k];
      if (c >= block.cols) throw std::runtime_error("output block " + block.name + ": a column out of range");
      m(r, c) = values[k];
      if (mirror && c < block.rows && r < block.cols) m(c, r) = values[k];
    }
  return m;
}

}  // namespace robodiff::cli
