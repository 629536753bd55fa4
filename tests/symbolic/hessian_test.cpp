// Weighted Hessians (sum_i w_i d^2 f_i / dx^2, lower triangle) of traced dynamics against
// central differences of the symbolic Jacobian, with the weights as constants and as
// graph inputs; the Hessian of a scalar cost; its sparsity pattern.
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/hessian.hpp"
#include "robodiff/symbolic/tracer.hpp"
#include "support/golden.hpp"

namespace robodiff::symbolic {
namespace {

using testing::matricesAgree;

class HessianOfRnea : public ::testing::Test {
 protected:
  void SetUp() override {
    GeneratorOptions options;
    options.joints = 5;
    options.seed = 21;
    options.prismatic_fraction = 0.4;
    model = loadUrdfString(generateRobotUrdf(options), RootJoint::Fixed, "chain5");
    q_ = tracer.addInputs("q", model.nq);
    v_ = tracer.addInputs("v", model.nv);
    a_ = tracer.addInputs("a", model.nv);
    w_ = tracer.addInputs("w", model.nv);  // multipliers, as an optimiser passes them
    Data<Sym> data(model);
    tau = tracer.outputs(rnea(model, data, q_, v_, a_));
    wrt = tracer.indices({"q", "v"});
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    x.resize(4 * model.nv);
    for (double& e : x) e = u(rng);
  }

  // The weighted Hessian's value, full and symmetric, at `at`.
  Eigen::MatrixXd value(const Hessian& h, const std::vector<double>& at) {
    Eigen::MatrixXd m(h.n, h.n);
    const std::vector<double> lower = graph.evaluate(h.lower, at);
    for (int i = 0, k = 0; i < h.n; ++i)
      for (int j = 0; j <= i; ++j, ++k) m(i, j) = m(j, i) = lower[k];
    return m;
  }
  // Central differences of w^T J (J = d tau / d wrt, symbolic) along each wrt input.
  Eigen::MatrixXd differencesOfJacobian(const std::vector<double>& w, double h = 1e-6) {
    const Jacobian jac = jacobian(graph, tau, wrt);
    const int n = static_cast<int>(wrt.size());
    Eigen::MatrixXd d(n, n);
    for (int j = 0; j < n; ++j) {
      std::vector<double> xp = x, xm = x;
      xp[wrt[j]] += h;
      xm[wrt[j]] -= h;
      const std::vector<double> jp = graph.evaluate(jac.entries, xp), jm = graph.evaluate(jac.entries, xm);
      for (int c = 0; c < n; ++c) {
        double s = 0;
        for (int r = 0; r < jac.rows; ++r) s += w[r] * (jp[r * n + c] - jm[r * n + c]);
        d(c, j) = s / (2 * h);
      }
    }
    return d;
  }

  Model model;
  Graph graph;
  Tracer tracer{graph};
  VecX<Sym> q_, v_, a_, w_;
  std::vector<NodeId> tau;
  std::vector<std::uint32_t> wrt;
  std::vector<double> x;
};

TEST_F(HessianOfRnea, WeightsAsInputs) {
  const Hessian h = weightedHessian(graph, tau, tracer.outputs(w_), wrt);
  ASSERT_EQ(h.n, 2 * model.nv);
  ASSERT_EQ(h.lower.size(), static_cast<std::size_t>(h.n * (h.n + 1) / 2));
  const std::vector<double> w(x.begin() + 3 * model.nv, x.end());
  EXPECT_TRUE(matricesAgree(value(h, x), differencesOfJacobian(w), 1e-6));
  // Other multipliers, same graph: the weights are inputs.
  for (int k = 3 * model.nv; k < 4 * model.nv; ++k) x[k] = 0.5 - x[k];
  const std::vector<double> w2(x.begin() + 3 * model.nv, x.end());
  EXPECT_TRUE(matricesAgree(value(h, x), differencesOfJacobian(w2), 1e-6));
}

TEST_F(HessianOfRnea, ConstantWeightsAndBothModes) {
  const std::vector<double> w = {1.0, -0.5, 2.0, 0.25, -1.5};
  ASSERT_EQ(static_cast<int>(w.size()), model.nv);
  const Eigen::MatrixXd fd = differencesOfJacobian(w);
  for (JacobianMode mode : {JacobianMode::Forward, JacobianMode::Reverse, JacobianMode::Automatic}) {
    SCOPED_TRACE(toString(mode));
    const Hessian h = weightedHessian(graph, tau, w, wrt, mode);
    EXPECT_TRUE(matricesAgree(value(h, x), fd, 1e-6));
  }
}

TEST_F(HessianOfRnea, SparsityOfTheLowerTriangle) {
  const Hessian h = weightedHessian(graph, tau, tracer.outputs(w_), wrt);
  const SparsityPattern p = h.pattern();
  const int n = model.nv;
  for (int r = 0; r < p.rows; ++r)
    for (int i = p.row_ptr[r]; i < p.row_ptr[r + 1]; ++i) EXPECT_LE(p.col_idx[i], r);
  EXPECT_GT(p.nnz(), 0);
  // The sparse values are the dense ones; outside the pattern the Hessian is zero.
  const std::vector<double> nz = graph.evaluate(h.nonzeros(), x);
  const Eigen::MatrixXd dense = value(h, x);
  for (int r = 0, k = 0; r < p.rows; ++r)
    for (int i = p.row_ptr[r]; i < p.row_ptr[r + 1]; ++i, ++k) EXPECT_EQ(nz[k], dense(r, p.col_idx[i]));
  for (int r = 0; r < 2 * n; ++r)
    for (int c = 0; c <= r; ++c)
      if (!p.contains(r, c)) {
        EXPECT_EQ(dense(r, c), 0.0);
      }
}

TEST(HessianOfACost, KineticEnergyInVIsTheMassMatrix) {
  // T = 1/2 v^T M(q) v: d^2 T / dv^2 = M(q), and d^2 T / dq^2 against differences.
  GeneratorOptions options;
  options.kind = RobotKind::Tree;
  options.tree = "2x3";
  options.seed = 8;
  const Model model = loadUrdfString(generateRobotUrdf(options), RootJoint::Fixed, "tree");
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> q = tracer.addInputs("q", model.nq), v = tracer.addInputs("v", model.nv);
  Data<Sym> data(model);
  const Sym energy = 0.5 * v.dot(crba(model, data, q) * v);
  const NodeId cost = tracer.output(energy);
  const Hessian hv = hessian(graph, cost, tracer.indices({"v"}));
  std::mt19937_64 rng(1);
  const Eigen::VectorXd qd = randomConfiguration(model, rng), vd = Eigen::VectorXd::LinSpaced(model.nv, -1, 1);
  std::vector<double> at(qd.data(), qd.data() + qd.size());
  at.insert(at.end(), vd.data(), vd.data() + vd.size());
  Data<double> dd(model);
  const Eigen::MatrixXd M = crba(model, dd, qd);
  for (int i = 0; i < model.nv; ++i)
    for (int j = 0; j < model.nv; ++j) EXPECT_NEAR(graph.evaluate({hv(i, j)}, at)[0], M(i, j), 1e-12 * M.norm());
  // Branches do not interact: the pattern of M, lower triangle.
  for (int i = 0; i < model.nv; ++i)
    for (int j = 0; j <= i; ++j) EXPECT_EQ(hv.pattern().contains(i, j), model.supports(j, i)) << i << ", " << j;

  const Hessian hq = hessian(graph, cost, tracer.indices({"q"}));
  const std::vector<NodeId> grad = gradient(graph, cost, tracer.indices({"q"}));
  const double h = 1e-6;
  for (int j = 0; j < model.nv; ++j) {
    std::vector<double> p = at, m = at;
    p[j] += h;
    m[j] -= h;
    const std::vector<double> gp = graph.evaluate(grad, p), gm = graph.evaluate(grad, m);
    for (int i = 0; i < model.nv; ++i)
      EXPECT_NEAR(graph.evaluate({hq(i, j)}, at)[0], (gp[i] - gm[i]) / (2 * h), 1e-6) << i << ", " << j;
  }
}

}  // namespace
}  // namespace robodiff::symbolic
