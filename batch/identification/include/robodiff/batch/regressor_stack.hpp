#pragma once
// The regressor, generated like any other function (spec {"function": "regressor",
// "outputs": [{"kind": "value"}]}, compiled through the cache or interpreted), evaluated
// at every sample on all cores and stacked:
//   tau_stack = W pi,  W = [Y(q_1, v_1, a_1); ...; Y(q_N, v_N, a_N)]   ((N nv) x (10 njoints))
// Rows of sample k are k*nv .. k*nv + nv - 1, in the model's velocity order; columns
// follow ParameterLayout.

#include <cstddef>
#include <functional>
#include <string>

#include <Eigen/Core>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/measured_samples.hpp"

namespace robodiff::batch {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct RegressorStack {
  RowMajorMatrix W;     // (N nv) x (10 njoints), as the function wrote it (row-major per sample)
  Eigen::VectorXd tau;  // N nv, the measured torques in the same row order
  int nv = 0;

  std::size_t samples() const { return nv > 0 ? static_cast<std::size_t>(W.rows() / nv) : 0; }
};

// The spec of the regressor's value.
FunctionSpec regressorSpec();

// The regressor of `model` (loaded from `urdf_text`) on the chosen backend.
BatchFunction openRegressor(const Model& model, const std::string& urdf_text, bool floating_base,
                            const BatchFunctionOptions& options = {});

// W and tau over samples [begin, end) (all by default). `cancelled` and `progress` as in
// BatchFunction::evaluateMany.
RegressorStack stackRegressor(const BatchFunction& regressor, const Model& model, const MeasuredSamples& samples,
                              std::size_t begin = 0, std::size_t end = static_cast<std::size_t>(-1),
                              const std::function<bool()>& cancelled = {},
                              const std::function<void(std::uint64_t done)>& progress = {});

}  // namespace robodiff::batch
