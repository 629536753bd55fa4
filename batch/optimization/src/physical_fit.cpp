// fitPhysicalParameters: the log-Cholesky program solved with Ipopt, and its report.
#include "robodiff/batch/physical_fit.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>

namespace robodiff::batch {

PhysicalFitResult fitPhysicalParameters(const NormalEquations& data, const Eigen::VectorXd& prior,
                                        const PhysicalFitOptions& options) {
  PhysicalFitResult result;
  const auto start = std::chrono::steady_clock::now();
  const double rows = static_cast<double>(std::max<std::int64_t>(data.rows, 1));
  const double lambda = options.regularization * PhysicalFitOptions::kRegularizationReferenceRows / rows;
  PhysicalFitProgram program(data, prior, lambda, options.divergence_weight, options.on_iteration);
  result.setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.projected_prior_bodies = program.projectedBodies();

  const IpoptResult solved = solveWithIpopt(program, options.ipopt);
  result.success = solved.success;
  result.cancelled = solved.cancelled;
  result.status = solved.status;
  result.iterations = solved.iterations;
  result.seconds = solved.seconds;

  // Ipopt's final point; its starting point if it has none (stopped before the first step).
  result.theta = solved.x.size() == static_cast<std::size_t>(program.variableCount())
                     ? Eigen::Map<const Eigen::VectorXd>(solved.x.data(), program.variableCount()).eval()
                     : program.startTheta();
  result.parameters = program.parameters(result.theta);
  result.objective = program.objective({result.theta.data(), static_cast<std::size_t>(result.theta.size())});
  result.data_residual = program.dataResidual(result.parameters);
  result.residual_rms = data.rows > 0 ? std::sqrt(result.data_residual / static_cast<double>(data.rows)) : 0.0;
  result.regularization_term = program.regularization(result.parameters);
  result.validity = checkValidity(result.parameters);
  return result;
}

}  // namespace robodiff::batch
