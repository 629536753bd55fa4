// Tracing the log-Cholesky map and generating its Jacobian and weighted Hessian, run by
// robodiff's interpreter.
#include "robodiff/batch/physical_log_cholesky_derivatives.hpp"

#include <algorithm>
#include <memory>
#include <utility>

#include "robodiff/batch/physical_log_cholesky.hpp"
#include "robodiff/codegen/function_definition.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/hessian.hpp"
#include "robodiff/symbolic/sym.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::batch {

using codegen::OutputBlock;
using symbolic::NodeId;
using symbolic::Sym;

struct LogCholeskyDerivatives::Built {
  std::unique_ptr<symbolic::Graph> graph = std::make_unique<symbolic::Graph>();
  codegen::FunctionDefinition value_jacobian, weighted_hessian;
};

LogCholeskyDerivatives::Built LogCholeskyDerivatives::trace() {
  Built built;
  symbolic::Graph& graph = *built.graph;
  symbolic::Tracer tracer(graph);
  const BodyVector<Sym> theta = tracer.addInputs("theta", 10);
  const VecX<Sym> weights = tracer.addInputs("weights", 10);
  const std::vector<NodeId> pi = tracer.outputs(parametersFromLogCholesky<Sym>(theta));
  const std::vector<std::uint32_t> wrt = tracer.indices({"theta"});

  const symbolic::Jacobian jacobian = symbolic::jacobian(graph, pi, wrt);
  const symbolic::Hessian hessian = symbolic::weightedHessian(graph, pi, tracer.outputs(weights), wrt);
  std::vector<NodeId> full;  // the dense symmetric matrix from its lower triangle
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) full.push_back(hessian(i, j));

  built.value_jacobian.name = "log_cholesky_value_jacobian";
  built.value_jacobian.inputs = {{"theta", 10}};
  built.value_jacobian.outputs = {OutputBlock::dense("pi", 10, 1, pi),
                                  OutputBlock::dense("jacobian", 10, 10, jacobian.entries)};
  built.weighted_hessian.name = "log_cholesky_weighted_hessian";
  built.weighted_hessian.inputs = {{"theta", 10}, {"weights", 10}};
  built.weighted_hessian.outputs = {OutputBlock::dense("hessian", 10, 10, std::move(full))};
  return built;
}

LogCholeskyDerivatives::LogCholeskyDerivatives() : LogCholeskyDerivatives(trace()) {}

LogCholeskyDerivatives::LogCholeskyDerivatives(Built built)
    : graph_size_(built.graph->size()),
      value_jacobian_(*built.graph, std::move(built.value_jacobian)),
      weighted_hessian_(*built.graph, std::move(built.weighted_hessian)),
      work_(std::max(value_jacobian_.workSize(), weighted_hessian_.workSize())) {}

void LogCholeskyDerivatives::valueAndJacobian(const Eigen::Matrix<double, 10, 1>& theta,
                                              Eigen::Matrix<double, 10, 1>& pi,
                                              Eigen::Matrix<double, 10, 10>& jacobian) const {
  // The interpreter writes row-major blocks.
  Eigen::Matrix<double, 10, 10, Eigen::RowMajor> rows;
  const double* in[] = {theta.data()};
  double* out[] = {pi.data(), rows.data()};
  value_jacobian_.evaluate(in, out, work_.data());
  jacobian = rows;
}

Eigen::Matrix<double, 10, 10> LogCholeskyDerivatives::weightedHessian(
    const Eigen::Matrix<double, 10, 1>& theta, const Eigen::Matrix<double, 10, 1>& weights) const {
  Eigen::Matrix<double, 10, 10, Eigen::RowMajor> rows;
  const double* in[] = {theta.data(), weights.data()};
  double* out[] = {rows.data()};
  weighted_hessian_.evaluate(in, out, work_.data());
  return rows;
}

}  // namespace robodiff::batch
