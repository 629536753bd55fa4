// ABA's articulated inertias, traced, are symmetric node for node: the update
// Ia - U D^-1 U^T and the transform to the parent (SE3::actOnSymmetric) compute their
// symmetric blocks on one side of the diagonal and mirror them, so the graph holds each
// entry once. Computed as full products, (r, c) and (c, r) are different expressions of
// the same value, and the free-flying Talos's ABA value took 14,385 operations instead
// of 12,849.
#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::symbolic {
namespace {

Model humanoid(RootJoint root) {
  GeneratorOptions o;
  o.kind = RobotKind::Tree;
  o.tree = "humanoid";
  o.seed = 6;
  return loadUrdfString(generateRobotUrdf(o), root, "humanoid");
}

// A symmetric 6 x 6 whose 21 entries on and above the diagonal are x[0..20].
Mat6<Sym> symmetricOf(const VecX<Sym>& x) {
  Mat6<Sym> m;
  for (int r = 0, k = 0; r < 6; ++r)
    for (int c = r; c < 6; ++c, ++k) m(r, c) = m(c, r) = x[k];
  return m;
}

TEST(SymmetricInertia, ArticulatedInertiasAreSymmetricNodeForNode) {
  for (RootJoint root : {RootJoint::Fixed, RootJoint::FreeFlyer}) {
    const Model model = humanoid(root);
    Graph graph;
    Tracer tracer(graph);
    const VecX<Sym> q = tracer.addInputs("q", model.nq), v = tracer.addInputs("v", model.nv),
                    tau = tracer.addInputs("tau", model.nv);
    Data<Sym> data(model);
    aba(model, data, q, v, tau);
    for (int j = 0; j < model.njoints(); ++j)
      for (int r = 0; r < 6; ++r)
        for (int c = r + 1; c < 6; ++c)
          EXPECT_EQ(data.Ia[j](r, c).nodeIn(graph), data.Ia[j](c, r).nodeIn(graph))
              << "joint " << j << " (" << r << ", " << c << ")";
  }
}

TEST(SymmetricInertia, TheArticulatedUpdateIsSymmetricNodeForNode) {
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> x = tracer.addInputs("x", 21 + 6);
  const Mat6<Sym> ia = symmetricOf(x);
  JointBlock<Sym> u(6, 1);
  for (int r = 0; r < 6; ++r) u(r, 0) = ia(r, 5);  // a revolute joint about z
  const JointBlock<Sym> udinv = u / ia(5, 5);
  const Mat6<Sym> out = articulatedUpdate(ia, udinv, u);
  for (int r = 0; r < 6; ++r)
    for (int c = r + 1; c < 6; ++c) EXPECT_EQ(out(r, c).nodeIn(graph), out(c, r).nodeIn(graph)) << r << ", " << c;
  const std::vector<NodeId> outputs = tracer.outputs(Eigen::Map<const VecX<Sym>>(out.data(), 36));
  // 6 quotients, 21 products and 21 differences (entries of the last row and column are 0).
  EXPECT_LE(coneSize(graph, outputs).operations, 6u + 21u + 21u);
}

TEST(SymmetricInertia, ActOnSymmetricKeepsASymmetricMatrixSymmetricAndEqualsTheFullProduct) {
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> x = tracer.addInputs("x", 21 + 6);
  const Mat6<Sym> y = symmetricOf(x);
  const SE3<Sym> m{Eigen::AngleAxis<double>(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix().cast<Sym>(),
                   Vec3<Sym>(x[21], x[22], x[23])};
  const Mat6<Sym> out = m.actOnSymmetric(y);
  for (int r = 0; r < 6; ++r)
    for (int c = r + 1; c < 6; ++c) EXPECT_EQ(out(r, c).nodeIn(graph), out(c, r).nodeIn(graph)) << r << ", " << c;
  // The same in doubles against X^T-style full products: X* Y X*^T with the force transform.
  Eigen::Matrix<double, 6, 6> yd;
  for (int r = 0, k = 0; r < 6; ++r)
    for (int c = r; c < 6; ++c, ++k) yd(r, c) = yd(c, r) = 0.1 * (k + 1) + (r == c ? 3.0 : 0.0);
  const Eigen::Matrix3d rot = Eigen::AngleAxis<double>(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d p(0.3, -0.2, 0.5);
  const SE3<double> md{rot, p};
  Eigen::Matrix3d px;
  px << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
  Eigen::Matrix<double, 6, 6> xf = Eigen::Matrix<double, 6, 6>::Zero();  // force transform, [linear; angular]
  xf.block<3, 3>(0, 0) = rot;
  xf.block<3, 3>(3, 3) = rot;
  xf.block<3, 3>(3, 0) = px * rot;
  const Eigen::Matrix<double, 6, 6> expected = xf * yd * xf.transpose();
  EXPECT_LT((md.actOnSymmetric(yd) - expected).norm(), 1e-12 * expected.norm());
}

}  // namespace
}  // namespace robodiff::symbolic
