// Stacking the generated regressor over samples.
#include "robodiff/batch/regressor_stack.hpp"

#include <algorithm>
#include <vector>

#include "robodiff/batch/identification_error.hpp"
#include "robodiff/batch/parameter_layout.hpp"

namespace robodiff::batch {

FunctionSpec regressorSpec() {
  return parseFunctionSpec(R"({"function": "regressor", "outputs": [{"kind": "value"}]})", "<regressor spec>");
}

BatchFunction openRegressor(const Model& model, const std::string& urdf_text, bool floating_base,
                            const BatchFunctionOptions& options) {
  return BatchFunction::open(model, urdf_text, floating_base, regressorSpec(), options);
}

RegressorStack stackRegressor(const BatchFunction& regressor, const Model& model, const MeasuredSamples& samples,
                              std::size_t begin, std::size_t end, const std::function<bool()>& cancelled,
                              const std::function<void(std::uint64_t done)>& progress) {
  end = std::min(end, samples.size());
  if (begin > end) begin = end;
  const std::size_t n = end - begin;
  const int nv = model.nv, cols = kParametersPerBody * model.njoints();
  if (samples.q.rows() != model.nq || samples.v.rows() != nv || samples.a.rows() != nv || samples.tau.rows() != nv)
    throw IdentificationError(samples.source + ": the samples are sized for another model (nq " +
                              std::to_string(samples.q.rows()) + ", nv " + std::to_string(samples.v.rows()) +
                              "; the model has nq " + std::to_string(model.nq) + ", nv " + std::to_string(nv) + ")");
  const BlockLayout& value = regressor.output("value");
  if (value.sparse || static_cast<int>(value.rows) != nv || static_cast<int>(value.cols) != cols ||
      regressor.outputCount() != value.size)
    throw IdentificationError("the regressor function's output is not the dense nv x 10 njoints value");

  // Inputs knot by knot, each block at its offset.
  const std::size_t in_count = regressor.inputCount();
  std::vector<double> in(n * in_count);
  const std::uint32_t q_at = regressor.input("q").offset, v_at = regressor.input("v").offset,
                      a_at = regressor.input("a").offset;
  for (std::size_t k = 0; k < n; ++k) {
    double* knot = in.data() + k * in_count;
    const auto s = static_cast<Eigen::Index>(begin + k);
    Eigen::Map<Eigen::VectorXd>(knot + q_at, model.nq) = samples.q.col(s);
    Eigen::Map<Eigen::VectorXd>(knot + v_at, nv) = samples.v.col(s);
    Eigen::Map<Eigen::VectorXd>(knot + a_at, nv) = samples.a.col(s);
  }

  RegressorStack stack;
  stack.nv = nv;
  // The function writes each knot's nv x cols block row-major: consecutive knots' blocks
  // are exactly the row-major stacked W.
  stack.W.resize(static_cast<Eigen::Index>(n) * nv, cols);
  const std::uint64_t done = regressor.evaluateMany(n, in.data(), stack.W.data(), cancelled, progress);
  if (done != n) throw IdentificationError("stacking the regressor was cancelled");
  stack.tau.resize(static_cast<Eigen::Index>(n) * nv);
  for (std::size_t k = 0; k < n; ++k)
    stack.tau.segment(static_cast<Eigen::Index>(k) * nv, nv) = samples.tau.col(static_cast<Eigen::Index>(begin + k));
  return stack;
}

}  // namespace robodiff::batch
