// The symbolic scalar: detached constants, recording into a graph, the math functions,
// comparisons that refuse to branch on values, and Eigen matrices of Sym.
#include <cmath>
#include <sstream>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "robodiff/spatial/math.hpp"
#include "robodiff/symbolic/sym.hpp"

namespace robodiff::symbolic {
namespace {

TEST(Sym, DetachedConstantsComputeAtOnce) {
  const Sym a(2.0), b = 3.0;
  const Sym c = a * b + 1.0 - b / 4.0;
  EXPECT_TRUE(c.isDetached());
  EXPECT_EQ(c.constantValue(), 2.0 * 3.0 + 1.0 - 3.0 / 4.0);
  EXPECT_EQ(sin(Sym(0.3)).constantValue(), std::sin(0.3));
  EXPECT_EQ(atan2(Sym(1.0), -2.0).constantValue(), std::atan2(1.0, -2.0));
  EXPECT_EQ(pow(Sym(2.0), 0.5).constantValue(), std::pow(2.0, 0.5));
  EXPECT_EQ(selectPositive(Sym(-1.0), 5.0, 7.0).constantValue(), 7.0);
  EXPECT_EQ(Sym().constantValue(), 0.0);
  EXPECT_THROW(Sym().node(), std::logic_error);
}

TEST(Sym, RecordsIntoTheGraphOfItsOperands) {
  Graph g;
  const Sym x(g, g.input(0)), y(g, g.input(1));
  const Sym f = 2.0 * x + sin(y) * x - 1.0;
  ASSERT_FALSE(f.isDetached());
  EXPECT_EQ(f.graph(), &g);
  EXPECT_FALSE(f.isConstant());
  EXPECT_DOUBLE_EQ(g.evaluate({f.node()}, {0.5, 0.25})[0], 2 * 0.5 + std::sin(0.25) * 0.5 - 1);
  // Simplification applies to traced values: x * 1, x + 0, x - x.
  EXPECT_EQ((x * 1.0).node(), x.node());
  EXPECT_EQ((x + 0.0).node(), x.node());
  EXPECT_TRUE((x - x).isConstant());
  EXPECT_EQ((x - x).constantValue(), 0.0);
  // Compound assignment and unary minus.
  Sym z = x;
  z += y;
  z *= 3.0;
  z -= 1.0;
  z /= y;
  EXPECT_DOUBLE_EQ(g.evaluate({z.node(), (-z).node()}, {0.5, 0.25})[1], -((0.5 + 0.25) * 3 - 1) / 0.25);
  // A detached constant joins the graph when asked for its node.
  EXPECT_EQ(Sym(1.0).nodeIn(g), g.one());
}

TEST(Sym, EveryMathFunctionRecordsItsOp) {
  Graph g;
  const Sym x(g, g.input(0)), y(g, g.input(1));
  const std::vector<std::pair<Sym, Op>> cases = {
      {sin(x), Op::Sin},   {cos(x), Op::Cos},     {tan(x), Op::Tan},     {asin(x), Op::Asin},
      {acos(x), Op::Acos}, {atan(x), Op::Atan},   {exp(x), Op::Exp},     {log(x), Op::Log},
      {sqrt(x), Op::Sqrt}, {tanh(x), Op::Tanh},   {abs(x), Op::Abs},     {atan2(x, y), Op::Atan2},
      {pow(x, y), Op::Pow}, {min(x, y), Op::Min}, {max(x, y), Op::Max},  {selectPositive(x, y, 1.0), Op::SelectPositive}};
  for (const auto& [value, op] : cases) EXPECT_EQ(g.node(value.node()).op, op) << toString(op);
  // Found by ADL through the customisation point the dynamics use.
  EXPECT_EQ(robodiff::math::sin(x).node(), sin(x).node());
  EXPECT_EQ(robodiff::math::sqrt(x).node(), sqrt(x).node());
}

TEST(Sym, ComparisonsWorkOnConstantsAndRefuseValues) {
  Graph g;
  const Sym x(g, g.input(0));
  const Sym two(g, g.constant(2.0));
  EXPECT_TRUE(Sym(1.0) < two);
  EXPECT_TRUE(two >= 2.0);
  EXPECT_TRUE(two == Sym(2.0));
  EXPECT_FALSE(two != 2.0);
  EXPECT_THROW((void)(x < 1.0), NonConstantComparison);
  EXPECT_THROW((void)(x == x), NonConstantComparison);
  try {
    (void)(x > two);
    FAIL();
  } catch (const NonConstantComparison& e) {
    EXPECT_NE(std::string(e.what()).find("must not branch on values"), std::string::npos);
  }
}

TEST(Sym, RefusesToMixGraphs) {
  Graph g1, g2;
  const Sym a(g1, g1.input(0)), b(g2, g2.input(0));
  EXPECT_THROW(a + b, std::invalid_argument);
  EXPECT_THROW(selectPositive(a, 1.0, b), std::invalid_argument);
  EXPECT_THROW(a.nodeIn(g2), std::invalid_argument);
}

TEST(Sym, EigenMatricesOfSym) {
  Graph g;
  Vec3<Sym> v(Sym(g, g.input(0)), Sym(g, g.input(1)), Sym(g, g.input(2)));
  const Mat3<Sym> I = Mat3<Sym>::Identity();
  const Vec3<Sym> w = I * v;  // products with detached constants fold away
  for (int k = 0; k < 3; ++k) EXPECT_EQ(w[k].node(), v[k].node());
  EXPECT_TRUE(Mat3<Sym>::Zero()(1, 2).isDetached());
  const Sym n2 = v.squaredNorm();
  const Vec3<Sym> scaled = 2.0 * v.cross(v * 0.5);  // Sym-double mixing in Eigen
  const MatX<Sym> big = MatX<Sym>::Identity(20, 20) * MatX<Sym>::Constant(20, 20, v[0]);  // GEMM path
  const std::vector<double> x = {0.5, -1.0, 2.0};
  EXPECT_DOUBLE_EQ(g.evaluate({n2.node()}, x)[0], 0.25 + 1.0 + 4.0);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(g.evaluate({scaled[k].nodeIn(g)}, x)[0], 0.0);  // v x v = 0
  EXPECT_EQ(big(3, 7).node(), v[0].node());
  std::ostringstream os;
  os << v[0] << ' ' << Sym(1.5);
  EXPECT_EQ(os.str(), "%" + std::to_string(v[0].node()) + " 1.5");
}

}  // namespace
}  // namespace robodiff::symbolic
