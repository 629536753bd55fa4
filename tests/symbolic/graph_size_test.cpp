// The size of traced dynamics and of their Jacobians (the operations generated code
// would hold) and the time to trace and differentiate them, in both modes, printed as a
// table; sanity bounds only. The numbers guide code generation (chunking, compile time)
// and the choice of mode.
#include <chrono>
#include <cstdio>

#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/cone.hpp"
#include "robodiff/symbolic/configuration.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/tracer.hpp"
#include "support/test_paths.hpp"

namespace robodiff::symbolic {
namespace {

double msSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// RNEA(q, v, a) or ABA(q, v, tau) traced, and its Jacobian w.r.t. [q (tangent), v, a/tau]
// in each mode; one row of the table.
void measure(const std::string& name, const Model& model, bool aba_function) {
  Graph graph;
  Tracer tracer(graph);
  auto t0 = std::chrono::steady_clock::now();
  const VecX<Sym> q0 = tracer.addInputs("q", model.nq);
  const bool floating = model.root == RootJoint::FreeFlyer;
  // With a fixed base q itself is the tangent coordinate: no q0 + dq nodes.
  const VecX<Sym> dq = floating ? tracer.addInputs("dq", model.nv) : VecX<Sym>();
  const VecX<Sym> v = tracer.addInputs("v", model.nv), x = tracer.addInputs("x", model.nv);
  const VecX<Sym> q = floating ? integrateSecondOrder(model, q0, dq) : q0;
  Data<Sym> data(model);
  const std::vector<NodeId> out = tracer.outputs(aba_function ? aba(model, data, q, v, x) : rnea(model, data, q, v, x));
  const double trace_ms = msSince(t0);
  const std::size_t value_ops = coneSize(graph, out).operations;
  const std::vector<std::uint32_t> wrt = tracer.indices({floating ? "dq" : "q", "v", "x"});

  std::printf("%-12s %3d %-5s %9zu %5.1f", name.c_str(), model.nv, aba_function ? "aba" : "rnea", value_ops, trace_ms);
  std::size_t ops[2] = {0, 0};
  int nnz[2] = {0, 0};
  int k = 0;
  for (JacobianMode mode : {JacobianMode::Reverse, JacobianMode::Forward}) {
    Graph g = graph;
    t0 = std::chrono::steady_clock::now();
    const Jacobian jac = jacobian(g, out, wrt, mode);
    const double ms = msSince(t0);
    ops[k] = coneSize(g, jac.entries).operations;
    nnz[k] = jac.pattern().nnz();
    std::printf(" %10zu %7.1f", ops[k], ms);
    ++k;
  }
  const JacobianMode automatic = jacobian(graph, out, wrt).mode;
  std::printf(" %5d %8s\n", nnz[0], toString(automatic));
  EXPECT_EQ(nnz[0], nnz[1]) << name;
  EXPECT_GT(std::min(ops[0], ops[1]), value_ops) << name;
  EXPECT_LT(std::min(ops[0], ops[1]), 2'000'000u) << name;
}

TEST(GraphSizes, Report) {
  std::vector<std::pair<std::string, Model>> robots;
  if (auto shared = testing::sharedDir()) {
    const std::string urdf = (*shared / "robots/panda_arm_fixed_fingers.urdf").string();
    robots.emplace_back("panda", loadUrdfFile(urdf));
    const std::string talos = (*shared / "robots/talos_reduced.urdf").string();
    robots.emplace_back("talos", loadUrdfFile(talos));
    robots.emplace_back("talos_ff", loadUrdfFile(talos, RootJoint::FreeFlyer));
  }
  GeneratorOptions arm;
  arm.joints = 7;
  robots.emplace_back("arm7", loadUrdfString(generateRobotUrdf(arm)));
  GeneratorOptions humanoid;
  humanoid.kind = RobotKind::Tree;
  humanoid.tree = "humanoid";
  robots.emplace_back("humanoid_ff", loadUrdfString(generateRobotUrdf(humanoid), RootJoint::FreeFlyer));

  std::printf("%-12s %3s %-5s %9s %5s %10s %7s %10s %7s %5s %8s\n", "robot", "nv", "fn", "value_ops", "ms",
              "rev_ops", "rev_ms", "fwd_ops", "fwd_ms", "nnz", "auto");
  for (const auto& [name, model] : robots)
    for (bool aba_function : {false, true}) measure(name, model, aba_function);
}

}  // namespace
}  // namespace robodiff::symbolic
