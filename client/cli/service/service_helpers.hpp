// Small steps the service commands share: reading a file the user named, LoadModel and
// GetFunction with errors main can report, and a server block's doubles as a matrix.
#pragma once

#include <span>
#include <string>

#include <Eigen/Core>

#include "robodiff/schema/messages.hpp"
#include "service/service_connection.hpp"

namespace robodiff::cli {

// The file's text; throws std::runtime_error naming `option` and the path.
std::string readTextFile(const std::string& path, const std::string& option);

// LoadModel; throws ServiceError.
rpc::LoadModelReply loadModelOnServer(const ServiceConnection& c, const std::string& urdf_text, bool floating_base);

// GetFunction; throws ServiceError (a FAILED function comes back as its failure status).
rpc::GetFunctionReply getFunctionOnServer(const ServiceConnection& c, const std::string& model_id,
                                          const std::string& spec_json, bool wait);

// An output block's doubles (nnz of them) as its rows x cols matrix: dense row-major, or
// CSR with the missing entries 0; a sparse Hessian (its lower triangle) mirrored.
Eigen::MatrixXd blockMatrix(const rpc::OutputBlock& block, std::span<const double> values);

}  // namespace robodiff::cli
