// User functions on the project's own robots (examples/robots: arm7 fixed, quadruped
// with a free-flyer): every output kind of the built function (interpreted) against the
// double evaluation of the same expressions and central finite differences of it;
// derivatives through primitives' rules smaller than through their traces; the
// canonical form (the cache key) blind to define names, define order and whitespace.
#include <gtest/gtest.h>

#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/functions/reference.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::matricesAgree;

Model exampleRobot(const std::string& name, RootJoint root = RootJoint::Fixed) {
  return loadUrdfFile((testing::sourceDir() / "examples" / "robots" / (name + ".urdf")).string(), root);
}

// Every output of the built function against the reference at `samples` random states.
void expectMatchesReference(const Model& model, const std::string& json, int samples = 3, double rel = 1e-6,
                            double h_hessian = 1e-4, double value_rel = 1e-12) {
  const FunctionSpec spec = parseFunctionSpec(json);
  const BuiltFunction f = buildFunction(model, spec);
  codegen::Interpreter interpreter(*f.graph, f.definition);
  for (int s = 0; s < samples; ++s) {
    const std::vector<Eigen::VectorXd> variable = randomRuntimeInputs(model, spec, 100 + s);
    const std::vector<Eigen::VectorXd> all = completeInputs(spec, variable);
    const std::vector<Eigen::VectorXd> out = evaluateBlocks(interpreter, f.definition, variable);
    const std::vector<Eigen::MatrixXd> expected = userReferenceOutputs(model, spec, all, 1e-6, h_hessian);
    for (std::size_t k = 0; k < out.size(); ++k) {
      SCOPED_TRACE(f.definition.outputs[k].name + " at sample " + std::to_string(s));
      const Eigen::MatrixXd actual = blockMatrix(f.definition.outputs[k], out[k], spec.outputs[k].kind == OutputKind::Hessian);
      const bool exact = spec.user->outputs[k].kind == UserOutputKind::Value;
      EXPECT_TRUE(matricesAgree(actual, expected[k], exact ? value_rel : rel));
    }
  }
}

const char* kEulerStep = R"js({
  "inputs": {"q": "configuration", "v": "nv", "u": "nv", "dt": {"fixed": [0.01]}},
  "define": {"v_next": "v + dt * aba(q, v, u)", "q_next": "integrate(q, dt * v_next)"},
  "outputs": [
    {"name": "q_next", "kind": "value", "of": "q_next"},
    {"name": "v_next", "kind": "value", "of": "v_next"},
    {"name": "dv_next", "kind": "jacobian", "of": "v_next", "wrt": ["q", "v", "u"]},
    {"name": "dq_next", "kind": "jacobian", "of": "q_next", "wrt": ["q", "v", "u"], "layout": "sparse"}
  ]})js";

TEST(UserFunction, EulerStepOnAFixedArm) { expectMatchesReference(exampleRobot("arm7"), kEulerStep); }

TEST(UserFunction, EulerStepOnAFloatingQuadruped) {
  expectMatchesReference(exampleRobot("quadruped", RootJoint::FreeFlyer), kEulerStep, 2, 2e-6);
}

// Value outputs only: aba's value built both ways (ABA, and M^-1 (tau - nle) by M's tree
// factors) and the smaller kept; each way against the reference (ABA in doubles) and a
// function with a derivative output, where aba's value comes from the derivatives' sweep.
TEST(UserFunction, AValueOnlyStepKeepsTheSmallerOfAbaAndTheFactors) {
  const char* value_only = R"js({
    "inputs": {"q": "configuration", "v": "nv", "u": "nv", "dt": {"fixed": [0.01]}},
    "define": {"v_next": "v + dt * aba(q, v, u)", "q_next": "integrate(q, dt * v_next)"},
    "outputs": [{"name": "q_next", "kind": "value", "of": "q_next"}, {"name": "v_next", "kind": "value", "of": "v_next"}]})js";
  for (const Model& model : {exampleRobot("arm7"), exampleRobot("quadruped", RootJoint::FreeFlyer)}) {
    SCOPED_TRACE(model.name);
    expectMatchesReference(model, value_only);
    const FunctionSpec spec = parseFunctionSpec(value_only);
    FunctionBuilderOptions articulated_options, factors_options;
    articulated_options.aba_value = AbaValueMethod::Articulated;
    factors_options.aba_value = AbaValueMethod::Factors;
    const BuiltFunction a = buildFunction(model, spec, articulated_options), f = buildFunction(model, spec, factors_options);
    const BuiltFunction chosen = buildFunction(model, spec);
    EXPECT_NE(builtOperations(a), builtOperations(f));
    EXPECT_EQ(builtOperations(chosen), std::min(builtOperations(a), builtOperations(f)));
    codegen::Interpreter ia(*a.graph, a.definition), jf(*f.graph, f.definition);
    const std::vector<Eigen::VectorXd> x = randomRuntimeInputs(model, spec, 7);
    const std::vector<Eigen::VectorXd> ya = evaluateBlocks(ia, a.definition, x), yf = evaluateBlocks(jf, f.definition, x);
    for (std::size_t k = 0; k < ya.size(); ++k) EXPECT_TRUE(matricesAgree(yf[k], ya[k], 1e-12));
  }
  // With a Jacobian, the option changes nothing: aba's value is the sweep's.
  const Model arm = exampleRobot("arm7");
  FunctionBuilderOptions articulated_options;
  articulated_options.aba_value = AbaValueMethod::Articulated;
  EXPECT_EQ(builtOperations(buildFunction(arm, parseFunctionSpec(kEulerStep), articulated_options)),
            builtOperations(buildFunction(arm, parseFunctionSpec(kEulerStep))));
}

// aba's torque tangent columns with one entry (u, v's diagonal terms) take M^-1's columns,
// denser ones (sum(u) * v) join the solve; both kinds in one column for v.
TEST(UserFunction, AbaOfATorqueMixingInputs) {
  const char* spec = R"js({
    "inputs": {"q": "configuration", "v": "nv", "u": "nv"},
    "define": {"ddq": "aba(q, v, 2 * u - 3 * v + 0.5 * sin(v) + 0.1 * sum(u) * v)"},
    "outputs": [{"name": "ddq", "kind": "value", "of": "ddq"},
                {"name": "J", "kind": "jacobian", "of": "ddq", "wrt": ["q", "v", "u"]}]})js";
  expectMatchesReference(exampleRobot("arm7"), spec);
  // The quadruped's ABA: the generated sums and the reference's round apart by up to
  // 1.7e-12 relative on entries near 1 (its mass matrix amplifies rounding).
  expectMatchesReference(exampleRobot("quadruped", RootJoint::FreeFlyer), spec, 2, 2e-6, 1e-4, 5e-12);
}

TEST(UserFunction, TrackingCostGradientAndHessian) {
  for (RootJoint root : {RootJoint::Fixed, RootJoint::FreeFlyer})
    expectMatchesReference(exampleRobot("arm7", root), R"js({
      "inputs": {"q": "configuration", "tau": "nv", "target": 3},
      "define": {"e": "frame_position(q, 'tool') - target", "cost": "sumsq(e) + 1e-3 * sumsq(tau)"},
      "outputs": [
        {"name": "cost", "kind": "value", "of": "cost"},
        {"name": "grad", "kind": "gradient", "of": "cost", "wrt": ["q", "tau"]},
        {"name": "hess", "kind": "hessian", "of": "cost", "wrt": ["q", "tau"]},
        {"name": "hess_sparse", "kind": "hessian", "of": "cost", "wrt": ["tau", "q"], "layout": "sparse"}
      ]})js", 2, 5e-5);  // the reference Hessian's second differences carry ~5e-8 of rounding noise
}

TEST(UserFunction, VectorJacobianProductAndWeightedHessian) {
  expectMatchesReference(exampleRobot("arm7"), R"js({
    "inputs": {"q": "configuration", "v": "nv", "lam": "nv", "w": "nv"},
    "define": {"f": "rnea(q, v, 0 * v) + crba(q) @ v"},
    "outputs": [
      {"name": "vjp", "kind": "vjp", "of": "f", "wrt": ["q", "v"], "lambda": "lam"},
      {"name": "whess", "kind": "hessian", "of": "f", "wrt": ["v"], "weights": "w"}
    ]})js", 2, 2e-5, 1e-2);  // f is quadratic in v: second differences are exact at any step
}

TEST(UserFunction, EveryMathFunctionAndOperator) {
  expectMatchesReference(exampleRobot("arm7"), R"js({
    "inputs": {"x": 3, "y": 3, "s": 1},
    "define": {
      "a": "sin(x) + cos(y) * tan(0.3 * x) - asin(0.5 * tanh(y)) + acos(0.4 * tanh(x)) + atan(x)",
      "b": "exp(0.5 * x) + log(2 + y^2) + sqrt(3 + x^2) + abs(y - 0.1) + softplus(x)",
      "c": "atan2(y, 2 + x^2) + pow(2 + x^2, 0.7) + min(x, y) + max(x, 0.5 * y) + select(x, y, 2 * y)",
      "M": "[x, y, a] @ [b, c, x].T + skew(cross(x, y)) + eye(3) * s",
      "r": "[sum(a) ; sumsq(b) ; norm(c) ; dot(x, y) ; M[1, 2] ; sum(M[0:2, 1:3]) ; x[2] / (2 + s^2)]"
    },
    "outputs": [
      {"name": "r", "kind": "value", "of": "r"},
      {"name": "J", "kind": "jacobian", "of": "r", "wrt": ["x", "y", "s"]},
      {"name": "M", "kind": "value", "of": "M"},
      {"name": "dM", "kind": "jacobian", "of": "M", "wrt": ["x"]}
    ]})js", 3, 1e-6);
}

TEST(UserFunction, PrimitivesAgainstDifferences) {
  for (RootJoint root : {RootJoint::Fixed, RootJoint::FreeFlyer})
    expectMatchesReference(exampleRobot("arm7", root), R"js({
      "inputs": {"q": "configuration", "v": "nv", "a": "nv", "q1": "configuration"},
      "define": {
        "e": "kinetic_energy(q, v) + potential_energy(q) + sum(com(q)) + sum(com_jacobian(q) @ v)",
        "f": "nle(q, v) + gravity(q) + minv(q) @ a + regressor(q, v, a) @ ones",
        "g": "[frame_velocity(q, v, 'tool'); frame_velocity(q, v, 'link4', 'LOCAL'); frame_jacobian(q, 'link3', 'WORLD') @ v]",
        "h": "[frame_rotation(q, 'tool')[0:3, 1]; frame_placement(q, 'link5')[2, 3]; difference(q, q1)]",
        "ones": "0 * regressor(q, v, a)[0, :].T + 1"
      },
      "outputs": [
        {"name": "e", "kind": "gradient", "of": "e", "wrt": ["q", "v"]},
        {"name": "f", "kind": "jacobian", "of": "f", "wrt": ["q", "v", "a"]},
        {"name": "g", "kind": "jacobian", "of": "g", "wrt": ["q", "v"]},
        {"name": "h", "kind": "jacobian", "of": "h", "wrt": ["q", "q1"]}
      ]})js", 2, 1e-4);  // measured: central differences (h = 1e-6) of f give 1.9e-5 for an
                         // entry that is 0, where f's Jacobian reaches ~360 (5.3e-5 of 1e-3 of it)
}

TEST(UserFunction, AHessianAloneAndTheWorldFrame) {
  expectMatchesReference(exampleRobot("arm7"), R"js({
    "inputs": {"q": "configuration", "v": "nv"},
    "outputs": [
      {"name": "h", "kind": "hessian", "of": "sumsq(com(q))", "wrt": ["q"]},
      {"name": "still", "kind": "value", "of": "[frame_velocity(q, v, 'world'); sum(frame_jacobian(q, 'world'))]"}
    ]})js", 2, 2e-4);
}

TEST(UserFunction, AModelFunctionSpecIsAOneLineUserFunction) {
  const Model model = exampleRobot("quadruped", RootJoint::FreeFlyer);
  const FunctionSpec builtin = parseFunctionSpec(
      R"js({"function": "aba", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "tau"]}]})js");
  const FunctionSpec user = parseFunctionSpec(R"js({"inputs": {"q": "configuration", "v": "nv", "tau": "nv"},
    "outputs": [{"name": "value", "kind": "value", "of": "aba(q, v, tau)"},
                {"name": "jacobian", "kind": "jacobian", "of": "aba(q, v, tau)", "wrt": ["q", "v", "tau"]}]})js");
  const BuiltFunction a = buildFunction(model, builtin), b = buildFunction(model, user);
  codegen::Interpreter ia(*a.graph, a.definition), ib(*b.graph, b.definition);
  const std::vector<Eigen::VectorXd> x = randomRuntimeInputs(model, builtin, 5);
  const std::vector<Eigen::VectorXd> ya = evaluateBlocks(ia, a.definition, x), yb = evaluateBlocks(ib, b.definition, x);
  EXPECT_TRUE(matricesAgree(yb[0], ya[0], 1e-12));
  EXPECT_TRUE(matricesAgree(yb[1], ya[1], 1e-10));
  // The same rule: M^-1 for tau's identity tangent, -M^-1 times the RNEA partials for q, v.
  std::cout << "ABA + J on the quadruped: " << builtOperations(a) << " operations built in, " << builtOperations(b)
            << " as a user function\n";
  EXPECT_LT(static_cast<double>(builtOperations(b)), 1.02 * static_cast<double>(builtOperations(a)));
}

TEST(UserFunction, PrimitiveRulesSaveOperations) {
  const Model model = exampleRobot("arm7");
  const BuiltFunction f = buildFunction(model, parseFunctionSpec(kEulerStep));
  ASSERT_GT(f.rule_operations, 0u);
  ASSERT_GT(f.traced_operations, 0u);
  std::cout << "Euler step on arm7: " << f.rule_operations << " operations with the primitives' rules, "
            << f.traced_operations << " differentiating their traces\n";
  EXPECT_LT(f.rule_operations * 2, f.traced_operations);
}

TEST(UserFunction, CanonicalFormIgnoresNamesOrderAndWhitespace) {
  const std::string renamed = R"js({"inputs": {"q": "configuration", "v": "nv", "u": "nv", "dt": {"fixed": [1e-2]}},
    "define": {"qn": "integrate(q,dt*vn)", "vn": "v+dt*aba( q , v , u )"},
    "outputs": [
      {"name": "q_next", "kind": "value", "of": "qn"},
      {"name": "v_next", "kind": "value", "of": "vn"},
      {"name": "dv_next", "kind": "jacobian", "of": "vn", "wrt": ["q", "v", "u"]},
      {"name": "dq_next", "kind": "jacobian", "of": "qn", "wrt": ["q", "v", "u"], "layout": "sparse"}]})js";
  const std::string inlined = R"js({"inputs": {"q": "configuration", "v": "nv", "u": "nv", "dt": {"fixed": [0.01]}},
    "outputs": [
      {"name": "q_next", "kind": "value", "of": "integrate(q, dt * (v + dt * aba(q, v, u)))"},
      {"name": "v_next", "kind": "value", "of": "v + dt * aba(q, v, u)"},
      {"name": "dv_next", "kind": "jacobian", "of": "v + dt * aba(q, v, u)", "wrt": ["q", "v", "u"]},
      {"name": "dq_next", "kind": "jacobian", "of": "integrate(q, dt * (v + dt * aba(q, v, u)))", "wrt": ["q", "v", "u"], "layout": "sparse"}]})js";
  const std::string key = normalizedSpecJson(parseFunctionSpec(kEulerStep));
  EXPECT_EQ(normalizedSpecJson(parseFunctionSpec(renamed)), key);
  EXPECT_EQ(normalizedSpecJson(parseFunctionSpec(inlined)), key);
  // Any change of meaning changes the key.
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"0.01", "0.02"}, {"v + dt", "v - dt"}, {"aba(q, v, u)", "aba(q, v, 2 * u)"}, {"[\"q\", \"v\", \"u\"]}", "[\"q\", \"u\"]}"},
           {"\"dv_next\"", "\"dv\""}, {"\"sparse\"", "\"dense\""}}) {
    std::string changed = kEulerStep;
    const std::size_t at = changed.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    changed.replace(at, from.size(), to);
    EXPECT_NE(normalizedSpecJson(parseFunctionSpec(changed)), key) << from << " -> " << to;
  }
}

}  // namespace
}  // namespace robodiff
