// The `robodiff` CLI as a client of a real robodiffd (load, eval, functions, health,
// warmup --server), run as a user runs it: a process per command, its output parsed back.
// `eval` must print what `compute --backend generated --derivatives` prints for the same
// robot, spec and state.
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "robodiff/schema/messages.hpp"
#include "robodiffd/robodiffd_process.hpp"
#include "shm/roudi_fixture.hpp"
#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

// Quick builds: O1, no -march=native.
const char* kRneaJacobian =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}],
        "build": {"optimization": "O1", "march_native": false}})";
// A sparse weighted Hessian (lower triangle in CSR, weights given at run time).
const char* kRneaHessianSparse =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q"]},
        {"kind": "hessian", "wrt": ["q"], "weights": "input", "layout": "sparse"}],
        "build": {"optimization": "O1", "march_native": false}})";

std::string cli(const std::string& args) { return shellQuote(cliPath().string()) + " " + args; }
std::string q(const std::filesystem::path& p) { return shellQuote(p.string()); }
std::string arm7() { return q(sourceDir() / "examples/robots/arm7.urdf"); }

// Every number of `want` (nested arrays) equals `got`'s to `tol` relative.
::testing::AssertionResult numbersAgree(const json& got, const json& want, double tol, const std::string& where) {
  if (want.is_number()) {
    if (!got.is_number()) return ::testing::AssertionFailure() << where << ": not a number: " << got.dump();
    const double a = got.get<double>(), b = want.get<double>();
    if (std::abs(a - b) > tol * (1 + std::abs(b)))
      return ::testing::AssertionFailure() << where << ": " << a << " vs " << b;
    return ::testing::AssertionSuccess();
  }
  if (!want.is_array() || !got.is_array() || got.size() != want.size())
    return ::testing::AssertionFailure() << where << ": shapes differ: " << got.dump().substr(0, 200) << " vs "
                                         << want.dump().substr(0, 200);
  for (std::size_t i = 0; i < want.size(); ++i) {
    auto r = numbersAgree(got[i], want[i], tol, where + "[" + std::to_string(i) + "]");
    if (!r) return r;
  }
  return ::testing::AssertionSuccess();
}

// eval's JSON has compute's keys with compute's numbers (backend, cache and transport aside).
void expectSameOutputs(const json& eval, const json& compute, double tol) {
  for (auto it = compute.begin(); it != compute.end(); ++it) {
    if (it.key() == "backend" || it.key() == "cache") continue;
    ASSERT_TRUE(eval.contains(it.key())) << it.key() << " missing in " << eval.dump().substr(0, 300);
    if (it.value().is_array()) EXPECT_TRUE(numbersAgree(eval[it.key()], it.value(), tol, it.key()));
    else EXPECT_EQ(eval[it.key()], it.value()) << it.key();
  }
  EXPECT_EQ(eval["backend"], "service");
}

json parsed(const ProcessResult& r) {
  try {
    return json::parse(r.out);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not JSON (" << e.what() << "): " << r.out << "\nstderr: " << r.err;
    return json();
  }
}

class CliService : public ::testing::Test {
 protected:
  // This process registers with RouDi (sharedRoudi); a RouDi stopped by SIGINT sends
  // SIGTERM to the processes registered with it.
  static void SetUpTestSuite() { signal(SIGTERM, SIG_IGN); }

  void SetUp() override {
    useLoopbackDds();
    unsetenv("ROBODIFF_SERVER");
  }

  TempDir dir_;
};

TEST_F(CliService, CommandsAgainstARealServer) {
  RoudiProcess& roudi = sharedRoudi();
  (void)roudi;
  const std::string service = "cli-test-" + std::to_string(getpid());
  RobodiffdProcess server(dir_ / "cache", dir_ / "robodiffd.log",
                          {"--roudi", "external", "--set", "iceoryx.service=" + service});
  ASSERT_TRUE(server.running());
  const std::string dds = "--server dds:" + std::to_string(testDomain());
  const std::string shm = "--server shm:" + service;
  const auto spec = dir_.file("rnea_jacobian.json", kRneaJacobian);

  // warmup --server: the server builds it; functions then says compiled.
  ProcessResult r = runCommand(cli("warmup " + dds + " --urdf " + arm7() + " --spec " + q(spec)));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err << server.log();
  EXPECT_NE(r.out.find("1 function: 1 built, 0 cached, 0 failed"), std::string::npos) << r.out;
  r = runCommand(cli("functions --json " + dds));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json functions = parsed(r);
  ASSERT_EQ(functions["functions"].size(), 1u) << r.out;
  EXPECT_EQ(functions["functions"][0]["state"], "READY");
  EXPECT_EQ(functions["functions"][0]["compiled"], true);
  EXPECT_EQ(functions["functions"][0]["function"], "rnea");
  const std::string function_id = functions["functions"][0]["function_id"];

  // eval (over DDS and over shared memory) equals compute's generated library.
  const std::string robot_spec_state = "--urdf " + arm7() + " --spec " + q(spec) + " --random-state 7";
  r = runCommand(cli("eval " + dds + " " + robot_spec_state));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json eval = parsed(r);
  r = runCommand(cli("compute --backend generated --no-cache --derivatives " + robot_spec_state));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json compute = parsed(r);
  ASSERT_TRUE(compute.contains("jacobian")) << compute.dump();
  expectSameOutputs(eval, compute, 1e-12);
  EXPECT_EQ(eval["transport"], "dds");
  EXPECT_EQ(eval["function_id"], function_id);
  r = runCommand(cli("eval " + shm + " " + robot_spec_state));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json eval_shm = parsed(r);
  EXPECT_EQ(eval_shm["transport"], "iceoryx");
  expectSameOutputs(eval_shm, compute, 1e-12);

  // A state file works as --state in compute; the table form names the blocks.
  const auto state = dir_.file("state.json", R"({"q": [0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7],
      "v": [1, 2, 3, 4, 5, 6, 7], "a": [-1, 0, 1, 0, -1, 0, 1]})");
  r = runCommand(cli("eval " + dds + " --urdf " + arm7() + " --spec " + q(spec) + " --state " + q(state)));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json eval_state = parsed(r);
  r = runCommand(cli("compute --backend generated --no-cache --derivatives --urdf " + arm7() + " --spec " + q(spec) +
                     " --state " + q(state)));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expectSameOutputs(eval_state, parsed(r), 1e-12);
  r = runCommand(cli("eval --format table " + shm + " " + robot_spec_state));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("jacobian"), std::string::npos) << r.out;

  // A sparse weighted Hessian (served by the interpreter until compiled): expanded and
  // mirrored as compute prints it.
  const auto hessian = dir_.file("rnea_hessian_sparse.json", kRneaHessianSparse);
  const std::string hessian_args = "--urdf " + arm7() + " --spec " + q(hessian) + " --random-state 3";
  r = runCommand(cli("eval " + dds + " " + hessian_args));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json eval_hessian = parsed(r);
  r = runCommand(cli("compute --backend generated --no-cache --derivatives " + hessian_args));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expectSameOutputs(eval_hessian, parsed(r), 1e-12);

  // A user function (the arm7 MPC knot: step, tracking cost, collision barrier) by its
  // inputs' names: eval prints every output under its name, as compute's interpreter does.
  const std::string knot = (sourceDir() / "examples/specs/arm7_mpc_knot.json").string();
  const std::string knot_args = "--urdf " + arm7() + " --spec " + q(knot) + " --random-state 5";
  r = runCommand(cli("eval " + shm + " " + knot_args));
  ASSERT_EQ(r.exit_code, 0) << r.err << server.log();
  const json eval_knot = parsed(r);
  r = runCommand(cli("compute --backend interpreted " + knot_args));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json compute_knot = parsed(r);
  for (const char* name : {"q_next", "dv_next", "tracking_hessian", "collision_gradient"})
    EXPECT_TRUE(compute_knot.contains(name)) << name;
  expectSameOutputs(eval_knot, compute_knot, 1e-10);

  // load prints the model id eval used.
  r = runCommand(cli("load --json " + shm + " --urdf " + arm7()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json model = parsed(r);
  EXPECT_EQ(model["model_id"], eval["model_id"]);
  EXPECT_EQ(model["nq"], 7);
  EXPECT_EQ(model["joints"].size(), 7u);
  EXPECT_FALSE(model["frames"].empty());
  r = runCommand(cli("load " + dds + " --urdf " + arm7()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(eval["model_id"].get<std::string>()), std::string::npos) << r.out;

  // functions: the table, and --model.
  r = runCommand(cli("functions " + dds));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(function_id.substr(0, 16)), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("READY"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("compiled"), std::string::npos) << r.out;
  r = runCommand(cli("functions --json " + shm + " --model " + eval["model_id"].get<std::string>()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(parsed(r)["functions"].size(), 3u) << r.out;  // the RNEA Jacobian, Hessian and the knot

  // A spec the server refuses: exit 1 with its status and message.
  const auto bad = dir_.file("bad.json", R"({"function": "no_such_function", "outputs": [{"kind": "value"}]})");
  r = runCommand(cli("eval " + dds + " --urdf " + arm7() + " --spec " + q(bad) + " --random-state 1"));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("robodiff: INVALID_ARGUMENT: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no_such_function"), std::string::npos) << r.err;
  r = runCommand(cli("warmup " + shm + " --urdf " + arm7() + " --spec " + q(spec) + " --spec " + q(bad)));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.err.find("no_such_function"), std::string::npos) << r.err;

  // health: readable, and every field in JSON.
  r = runCommand(cli("health " + shm));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("SERVING"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Evaluate"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\nfleet       role standalone\n"), std::string::npos) << r.out;  // FleetStatus
  r = runCommand(cli("health --json " + dds));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json health = parsed(r);
  EXPECT_EQ(health["state"], "SERVING");
  EXPECT_EQ(health["models_loaded"], 1);
  EXPECT_EQ(health["functions_loaded"], 3);
  ASSERT_EQ(health["methods"].size(), rpc::kMethodCount) << r.out;  // one per method, in Method order
  std::map<std::string, json> methods;
  for (const json& m : health["methods"]) methods[m["method"]] = m;
  EXPECT_GE(methods["LoadModel"]["requests"].get<int>(), 6);
  EXPECT_GE(methods["Evaluate"]["requests"].get<int>(), 5);
  EXPECT_GE(methods["GetFunction"]["errors"].get<int>(), 1);
  EXPECT_GE(methods["ListFunctions"]["requests"].get<int>(), 3);
  EXPECT_FALSE(health["errors"].empty());
  EXPECT_EQ(health["transports"].size(), 2u);
  EXPECT_TRUE(health.contains("cache_hits"));
  EXPECT_TRUE(health.contains("uptime_ns"));
  EXPECT_EQ(health["fleet"]["role"], "standalone") << r.out;
  EXPECT_TRUE(health["fleet"]["peers"].empty()) << r.out;
}

TEST_F(CliService, NoServerAndBadUsage) {
  // A domain no test uses: UNAVAILABLE, exit 3, within about the timeout.
  const std::string nobody = "--server dds:232 --timeout 1";
  auto started = Clock::now();
  ProcessResult r = runCommand(cli("health " + nobody));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_NE(r.err.find("robodiff: UNAVAILABLE: "), std::string::npos) << r.err;
  EXPECT_LT(Clock::now() - started, std::chrono::seconds(5));
  started = Clock::now();
  r = runCommand(cli("eval " + nobody + " --urdf " + arm7() + " --spec " +
                     q(sourceDir() / "examples/specs/rnea_jacobian.json") + " --random-state 1"));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  r = runCommand(cli("warmup " + nobody + " --urdf " + arm7() + " --spec " +
                     q(sourceDir() / "examples/specs/rnea_jacobian.json")));
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
  EXPECT_LT(Clock::now() - started, std::chrono::seconds(8));

  // Bad usage: exit 2.
  r = runCommand(cli("health --server nowhere"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("nowhere"), std::string::npos) << r.err;
  r = runCommand(cli("functions --server dds:999"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  r = runCommand("ROBODIFF_SERVER=bogus " + cli("health"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("ROBODIFF_SERVER"), std::string::npos) << r.err;
  r = runCommand(cli("warmup --server nowhere --urdf " + arm7() + " --spec x.json"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  r = runCommand(cli("eval --server dds:232 --urdf " + arm7() + " --spec " +
                     q(sourceDir() / "examples/specs/rnea_jacobian.json")));  // no state
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  r = runCommand(cli("load --server dds:232 --urdf /no/such.urdf"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  r = runCommand(cli("health --timeout -1"));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;

  // --help on every command, with the exit statuses.
  for (const std::string command : {"load", "eval", "functions", "health", "warmup"}) {
    r = runCommand(cli(command + " --help"));
    EXPECT_EQ(r.exit_code, 0) << command << r.err;
    EXPECT_NE(r.out.find("--server"), std::string::npos) << command << r.out;
    EXPECT_NE(r.out.find("3 no server reachable"), std::string::npos) << command << r.out;
  }
}

}  // namespace
}  // namespace robodiff::testing
