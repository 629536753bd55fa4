// The CppADCodeGen side, used the way Pinocchio's own codegen uses it: Pinocchio's
// templated algorithm taped with CppAD::AD<CppAD::cg::CG<double>>, the tape optimized,
// C generated (ModelCSourceGen: forward zero, and the Jacobian), compiled by the system
// gcc -O2 -march=native into a dynamic library (DynamicModelLibraryProcessor +
// GccCompiler), loaded and called through its GenericModel.
//
// Every library is built in a child process of its own (child_build.hpp): its wall time
// is the cold build (tape + generate + compile), measured_cc's log there gives
// the compiler's peak memory, and a build over the cap is killed and reported.
//
// Jacobians are w.r.t. [q in the tangent space, v, a or tau], as Pinocchio's analytic
// derivatives: the tape's inputs are [q, dq, v, a] with q' = integrate(q, dq), and the
// library's sparse Jacobian is asked for the (dense) block of the columns dq, v, a only,
// evaluated at dq = 0.
//
// The step rows (step_rows.hpp) are taped the same way: ABA, the semi-implicit Euler
// step and the frame-placement cost written on the CG scalar, for fixed-base robots whose
// configuration is their tangent space (nq = nv: the step's Jacobian rows are then the
// coordinates of q_next). step_cost_derivatives is not built: its Hessian is the exact
// one, and the check compares Gauss-Newton Hessians.
#include <pinocchio/codegen/cppadcg.hpp>  // first: Pinocchio's support of the CG scalar
#include <cppad/cg.hpp>

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/rnea.hpp>

#include <filesystem>
#include <memory>

#include "anchors.hpp"
#include "child_build.hpp"
#include "step_rows.hpp"

namespace anchors {
namespace {

namespace fs = std::filesystem;
using robodiff::cli::bench::AlignedDoubles;
using robodiff::cli::bench::doNotOptimize;
using robodiff::cli::bench::secondsPerCall;

using CGD = CppAD::cg::CG<double>;
using ADS = CppAD::AD<CGD>;
using ADVec = Eigen::Matrix<ADS, Eigen::Dynamic, 1>;
using ADMat = Eigen::Matrix<ADS, Eigen::Dynamic, Eigen::Dynamic>;

// What a row's library takes and gives.
struct CodegenShape {
  bool jacobian = false;   // value + Jacobian over [dq, v, a|tau] (inputs [q, dq, v, a|tau])
  bool q_only = false;     // CRBA and the frame Jacobian: inputs [q]
  int n_in = 0, n_out = 0;
  int jacobian_rows = 0;   // the outputs the Jacobian has rows for (nv, or 2nv for the step)
};

CodegenShape shapeOf(const std::string& row, const pinocchio::Model& m) {
  CodegenShape s;
  s.jacobian = row == "rnea_jacobian_dense" || row == "aba_jacobian" || row == "euler_step_jacobian";
  s.q_only = row == "crba_value" || row == "frame_jacobian_value";
  s.n_in = s.q_only ? m.nq : s.jacobian ? m.nq + 3 * m.nv : m.nq + 2 * m.nv;
  s.n_out = row == "crba_value" ? m.nv * m.nv : row == "frame_jacobian_value" ? 6 * m.nv : m.nv;
  if (isStepRow(row)) s.n_out = m.nq + m.nv + (row == "step_cost_value" ? 1 : 0);
  s.jacobian_rows = isStepRow(row) ? 2 * m.nv : m.nv;
  return s;
}

// The library's input vector at state s (dq = 0 for the Jacobian rows).
std::vector<double> inputAt(const std::string& row, const pinocchio::Model& m, const State& s) {
  const CodegenShape shape = shapeOf(row, m);
  std::vector<double> x(s.q.data(), s.q.data() + m.nq);
  if (shape.q_only) return x;
  if (shape.jacobian) x.insert(x.end(), m.nv, 0.0);
  const bool aba = row.rfind("aba", 0) == 0 || isStepRow(row);
  const Eigen::VectorXd& last = aba ? s.tau : s.a;
  x.insert(x.end(), s.v.data(), s.v.data() + m.nv);
  x.insert(x.end(), last.data(), last.data() + m.nv);
  return x;
}

// The Euler step (and, for step_cost_value, the cost l at q) on the CG scalar, put as
// [q_next; v_next (; l)].
template <class Put>
void tapeStep(const std::string& row, const pinocchio::ModelTpl<ADS>& model, pinocchio::DataTpl<ADS>& data,
              pinocchio::FrameIndex frame, const ADVec& q, const ADVec& v, const ADVec& u, Put& put) {
  const ADVec v_next = v + ADS(kStepDt) * pinocchio::aba(model, data, q, v, u);
  const ADVec q_next = pinocchio::integrate(model, q, ADVec(ADS(kStepDt) * v_next));
  put(q_next);
  put(v_next);
  if (row != "step_cost_value") return;
  pinocchio::forwardKinematics(model, data, q);
  pinocchio::updateFramePlacement(model, data, frame);
  ADS l = ADS(kControlWeight) * u.squaredNorm();
  for (int k = 0; k < 3; ++k) {
    const ADS e = data.oMf[frame].translation()[k] - ADS(kCostTarget[static_cast<size_t>(k)]);
    l += e * e;
  }
  put(Eigen::Matrix<ADS, 1, 1>::Constant(l));
}

// Records `row` through Pinocchio's templates on the CG scalar; returns the optimized tape.
std::unique_ptr<CppAD::ADFun<CGD>> tape(const std::string& row, const pinocchio::Model& model, const State& s) {
  using ADModel = pinocchio::ModelTpl<ADS>;
  const ADModel ad_model = model.cast<ADS>();
  pinocchio::DataTpl<ADS> ad_data(ad_model);
  const CodegenShape shape = shapeOf(row, model);
  const std::vector<double> x0 = inputAt(row, model, s);
  std::vector<ADS> x(x0.begin(), x0.end());
  CppAD::Independent(x);
  const int nq = model.nq, nv = model.nv;
  auto segment = [&](int begin, int n) {
    ADVec v(n);
    for (int i = 0; i < n; ++i) v[i] = x[begin + i];
    return v;
  };
  ADVec q = segment(0, nq);
  int at = nq;
  if (shape.jacobian) q = pinocchio::integrate(ad_model, q, segment(nq, nv)), at += nv;
  std::vector<ADS> y;
  auto put = [&](const auto& mat) {
    for (Eigen::Index c = 0; c < mat.cols(); ++c)
      for (Eigen::Index r = 0; r < mat.rows(); ++r) y.push_back(mat(r, c));
  };
  if (row == "rnea_value" || row == "rnea_jacobian_dense") {
    put(pinocchio::rnea(ad_model, ad_data, q, segment(at, nv), segment(at + nv, nv)));
  } else if (row == "aba_value" || row == "aba_jacobian") {
    put(pinocchio::aba(ad_model, ad_data, q, segment(at, nv), segment(at + nv, nv)));
  } else if (row == "crba_value") {
    pinocchio::crba(ad_model, ad_data, q);
    const ADMat M = ad_data.M.selfadjointView<Eigen::Upper>();
    put(M);
  } else if (row == "frame_jacobian_value") {
    ADMat J = ADMat::Zero(6, nv);
    pinocchio::computeFrameJacobian(ad_model, ad_data, q, lastFrame(model), pinocchio::LOCAL_WORLD_ALIGNED, J);
    put(J);
  } else if (isStepRow(row)) {
    tapeStep(row, ad_model, ad_data, lastFrame(model), q, segment(at, nv), segment(at + nv, nv), put);
  }
  auto fun = std::make_unique<CppAD::ADFun<CGD>>(x, y);
  fun->optimize("no_compare_op");
  return fun;
}

// Generates and compiles the library of `row` in the current directory (the child).
void generateAndCompile(const std::string& row, const pinocchio::Model& model, const State& s) {
  std::unique_ptr<CppAD::ADFun<CGD>> fun = tape(row, model, s);
  const CodegenShape shape = shapeOf(row, model);
  CppAD::cg::ModelCSourceGen<double> source(*fun, row);
  source.setCreateForwardZero(true);
  if (shape.jacobian) {
    std::vector<size_t> rows, cols;  // row-major, the columns [dq, v, a|tau]
    for (int r = 0; r < shape.jacobian_rows; ++r)
      for (int c = 0; c < 3 * model.nv; ++c) rows.push_back(r), cols.push_back(model.nq + c);
    source.setCreateSparseJacobian(true);
    source.setCustomSparseJacobianElements(rows, cols);
  }
  CppAD::cg::ModelLibraryCSourceGen<double> library(source);
  CppAD::cg::DynamicModelLibraryProcessor<double> processor(library, "anchor_" + row);
  CppAD::cg::GccCompiler<double> gcc(compilerCommand());
  gcc.setCompileFlags({"-O2", "-march=native"});
  gcc.setCompileLibFlags({"-O2", "-march=native", "-shared", "-rdynamic"});
  processor.createDynamicLibrary(gcc, false);
}

fs::path libraryPath(const fs::path& dir, const std::string& row) { return dir / ("anchor_" + row + ".so"); }

// A loaded library and its model, with preallocated input and output buffers.
struct LoadedModel {
  std::unique_ptr<CppAD::cg::LinuxDynamicLib<double>> lib;
  std::unique_ptr<CppAD::cg::GenericModel<double>> model;
  AlignedDoubles x, y, jac;  // on 64-byte boundaries, as robodiff bench's buffers
  const size_t *rows = nullptr, *cols = nullptr;

  void setInput(const std::vector<double>& values) { x.assign(values.begin(), values.end()); }
  void call(bool jacobian) {
    const CppAD::cg::ArrayView<const double> in(x.data(), x.size());
    model->ForwardZero(in, CppAD::cg::ArrayView<double>(y.data(), y.size()));
    if (jacobian) model->SparseJacobian(in, CppAD::cg::ArrayView<double>(jac.data(), jac.size()), &rows, &cols);
    doNotOptimize(y[0]);
    doNotOptimize(jac);
  }
};

Output outputOf(const std::string& row, const pinocchio::Model& m, LoadedModel& lm) {
  const CodegenShape shape = shapeOf(row, m);
  lm.call(shape.jacobian);
  Output o;
  const Eigen::Map<const Eigen::VectorXd> y(lm.y.data(), static_cast<Eigen::Index>(lm.y.size()));
  if (row == "crba_value") o.jacobian = Eigen::Map<const Eigen::MatrixXd>(lm.y.data(), m.nv, m.nv);
  else if (row == "frame_jacobian_value") o.jacobian = Eigen::Map<const Eigen::MatrixXd>(lm.y.data(), 6, m.nv);
  else o.value = y;
  if (shape.jacobian) {
    o.jacobian = Eigen::MatrixXd::Zero(shape.jacobian_rows, 3 * m.nv);
    for (size_t k = 0; k < lm.jac.size(); ++k)
      o.jacobian(static_cast<Eigen::Index>(lm.rows[k]), static_cast<Eigen::Index>(lm.cols[k]) - m.nq) = lm.jac[k];
  }
  return o;
}

}  // namespace

std::vector<std::string> codegenRowNames(bool step_rows) {
  std::vector<std::string> names = kRows;
  if (step_rows) names.insert(names.end(), kGeneratedStepRows.begin(), kGeneratedStepRows.end());
  return names;
}

std::vector<RowResult> runCppADCodeGen(const pinocchio::Model& model, const State& timed,
                                       const std::vector<State>& checks, const Timing& plan,
                                       const CodegenOptions& options) {
  std::vector<RowResult> rows;
  for (const std::string& name : codegenRowNames(options.step_rows)) {
    RowResult r;
    r.name = name;
    if (!options.only.empty() && std::find(options.only.begin(), options.only.end(), name) == options.only.end()) {
      r.status = "skipped";
      rows.push_back(std::move(r));
      continue;
    }
    const fs::path dir = fs::path(options.workdir) / name;
    if (!(options.reuse && reuseBuild(dir, libraryPath(dir, name), r))) {
      std::fprintf(stderr, "anchors_bench: CppADCodeGen building %s ...\n", name.c_str());
      const auto build = [&] { generateAndCompile(name, model, timed); };
      buildInChild(dir, libraryPath(dir, name), options.cap_seconds, build, r);
    }
    if (r.status != "ok" || options.build_only) {
      rows.push_back(std::move(r));
      continue;
    }
    LoadedModel lm;
    lm.lib = std::make_unique<CppAD::cg::LinuxDynamicLib<double>>(libraryPath(dir, name).string());
    lm.model = lm.lib->model(name);
    const CodegenShape shape = shapeOf(name, model);
    lm.y.resize(static_cast<size_t>(shape.n_out));
    lm.jac.resize(shape.jacobian ? static_cast<size_t>(3 * model.nv * shape.jacobian_rows) : 0);
    for (const State& s : checks) {
      lm.setInput(inputAt(name, model, s));
      r.outputs.push_back(outputOf(name, model, lm));
    }
    lm.setInput(inputAt(name, model, timed));
    r.us = 1e6 * secondsPerCall([&] { lm.call(shape.jacobian); }, plan);
    rows.push_back(std::move(r));
  }
  return rows;
}

}  // namespace anchors
