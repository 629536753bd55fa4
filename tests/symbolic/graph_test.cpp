// The expression graph: simplification at construction, hash-consing, evaluation and
// the node limit.
#include <cmath>

#include <gtest/gtest.h>

#include "robodiff/symbolic/graph.hpp"

namespace robodiff::symbolic {
namespace {

class Simplification : public ::testing::Test {
 protected:
  Graph g;
  NodeId x = g.input(0), y = g.input(1);
  NodeId neg(NodeId a) { return g.unary(Op::Neg, a); }
  NodeId add(NodeId a, NodeId b) { return g.binary(Op::Add, a, b); }
  NodeId sub(NodeId a, NodeId b) { return g.binary(Op::Sub, a, b); }
  NodeId mul(NodeId a, NodeId b) { return g.binary(Op::Mul, a, b); }
  NodeId div(NodeId a, NodeId b) { return g.binary(Op::Div, a, b); }
  NodeId c(double v) { return g.constant(v); }
};

TEST_F(Simplification, Identities) {
  EXPECT_EQ(mul(x, g.one()), x);
  EXPECT_EQ(mul(g.one(), x), x);
  EXPECT_EQ(mul(x, g.zero()), g.zero());
  EXPECT_EQ(add(x, g.zero()), x);
  EXPECT_EQ(add(g.zero(), x), x);
  EXPECT_EQ(sub(x, g.zero()), x);
  EXPECT_EQ(sub(x, x), g.zero());
  EXPECT_EQ(sub(g.zero(), x), neg(x));
  EXPECT_EQ(neg(neg(x)), x);
  EXPECT_EQ(div(x, x), g.one());
  EXPECT_EQ(div(x, g.one()), x);
  EXPECT_EQ(div(g.zero(), x), g.zero());
  EXPECT_EQ(g.binary(Op::Pow, x, g.one()), x);
  EXPECT_EQ(g.binary(Op::Pow, x, g.zero()), g.one());
  EXPECT_EQ(g.binary(Op::Min, x, x), x);
  EXPECT_EQ(g.binary(Op::Max, y, y), y);
}

TEST_F(Simplification, NegationsFoldIntoAddAndSub) {
  const NodeId a_minus_b = sub(x, y);
  EXPECT_EQ(add(x, neg(y)), a_minus_b);       // a + (-b) = a - b
  EXPECT_EQ(add(neg(y), x), a_minus_b);       // (-b) + a = a - b
  EXPECT_EQ(sub(x, neg(y)), add(x, y));       // a - (-b) = a + b
  EXPECT_EQ(neg(sub(x, y)), sub(y, x));       // -(a - b) = b - a
  EXPECT_EQ(mul(x, c(-1)), neg(x));           // x * -1 = -x
  EXPECT_EQ(mul(neg(x), neg(y)), mul(x, y));  // (-x)(-y) = xy
  EXPECT_EQ(mul(neg(x), y), neg(mul(x, y)));  // negations pulled out of products
  EXPECT_EQ(div(x, neg(y)), neg(div(x, y)));
  EXPECT_EQ(div(neg(x), y), neg(div(x, y)));
  EXPECT_EQ(g.unary(Op::Abs, neg(x)), g.unary(Op::Abs, x));
  EXPECT_EQ(g.unary(Op::Abs, g.unary(Op::Abs, x)), g.unary(Op::Abs, x));
}

TEST_F(Simplification, ConstantsFold) {
  const NodeId six = mul(c(2), c(3));
  EXPECT_EQ(g.node(six).op, Op::Constant);
  EXPECT_EQ(g.node(six).value, 6.0);
  EXPECT_EQ(six, c(6));  // constants are hash-consed by value
  EXPECT_EQ(g.node(g.unary(Op::Sin, c(0.5))).value, std::sin(0.5));
  EXPECT_EQ(g.node(g.binary(Op::Atan2, c(1), c(-2))).value, std::atan2(1.0, -2.0));
  EXPECT_EQ(c(-0.0), g.zero());  // one zero node
  EXPECT_EQ(g.selectPositive(c(1), x, y), x);
  EXPECT_EQ(g.selectPositive(c(-1), x, y), y);
  EXPECT_EQ(g.selectPositive(c(0), x, y), y);
  EXPECT_EQ(g.selectPositive(x, y, y), y);
}

TEST_F(Simplification, DivisionByAPowerOfTwoIsAnExactProduct) {
  EXPECT_EQ(div(x, c(4)), mul(x, c(0.25)));
  EXPECT_EQ(g.node(div(x, c(3))).op, Op::Div);  // 1/3 is not exact: stays a division
  EXPECT_EQ(g.binary(Op::Pow, x, c(2)), mul(x, x));
}

TEST_F(Simplification, HashConsingAndCanonicalOrder) {
  EXPECT_EQ(add(x, y), add(y, x));
  EXPECT_EQ(mul(x, y), mul(y, x));
  EXPECT_EQ(g.binary(Op::Min, x, y), g.binary(Op::Min, y, x));
  EXPECT_NE(sub(x, y), sub(y, x));
  EXPECT_NE(div(x, y), div(y, x));
  EXPECT_EQ(g.input(0), x);
  // sin and cos of one argument share the argument's node, and repeating is free.
  const NodeId arg = mul(x, y);
  const std::size_t before = g.size();
  const NodeId s = g.unary(Op::Sin, mul(y, x)), co = g.unary(Op::Cos, mul(x, y));
  EXPECT_EQ(g.node(s).args[0], arg);
  EXPECT_EQ(g.node(co).args[0], arg);
  EXPECT_EQ(g.size(), before + 2);
  EXPECT_EQ(g.unary(Op::Sin, arg), s);
  EXPECT_EQ(g.size(), before + 2);
}

TEST_F(Simplification, ArgumentsPrecedeTheirNodes) {
  NodeId acc = x;
  for (int i = 0; i < 50; ++i) acc = add(mul(acc, y), g.unary(Op::Cos, acc));
  for (NodeId id = 0; id < g.size(); ++id)
    for (int k = 0; k < arity(g.node(id).op); ++k) EXPECT_LT(g.node(id).args[k], id);
}

TEST(Graph, Evaluates) {
  Graph g;
  const NodeId x = g.input(0), y = g.input(1);
  const NodeId f = g.binary(Op::Add, g.unary(Op::Sin, x), g.binary(Op::Mul, x, y));
  const NodeId s = g.selectPositive(g.binary(Op::Sub, x, y), x, y);
  const std::vector<double> out = g.evaluate({f, s, x}, {0.7, -1.5});
  EXPECT_DOUBLE_EQ(out[0], std::sin(0.7) + 0.7 * -1.5);
  EXPECT_EQ(out[1], 0.7);
  EXPECT_EQ(out[2], 0.7);
  EXPECT_EQ(g.inputCount(), 2u);
  EXPECT_THROW(g.evaluate({f}, {0.7}), std::out_of_range);
}

TEST(Graph, StopsAtTheNodeLimitWithAResourceError) {
  Graph g;
  g.setNodeLimit(100);
  EXPECT_EQ(g.nodeLimit(), 100u);
  const NodeId x = g.input(0);
  const NodeId first = g.unary(Op::Sin, x);
  NodeId acc = first;
  try {
    for (int i = 0; i < 1000; ++i) acc = g.unary(Op::Sin, acc);
    FAIL() << "no GraphTooLarge";
  } catch (const GraphTooLarge& e) {
    EXPECT_EQ(e.limit(), 100u);
    EXPECT_NE(std::string(e.what()).find("100"), std::string::npos) << e.what();
  }
  EXPECT_EQ(g.size(), 100u);
  // The graph stays consistent: existing nodes are still found, and it evaluates.
  EXPECT_EQ(g.unary(Op::Sin, x), first);
  EXPECT_NO_THROW(g.evaluate({acc}, {0.3}));
  g.setNodeLimit(200);
  EXPECT_NO_THROW(g.unary(Op::Cos, acc));
}

}  // namespace
}  // namespace robodiff::symbolic
