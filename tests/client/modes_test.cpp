// The three ways to evaluate give the same answers and the same statuses: Local (the
// cached library in this process), Shm and Dds (robodiffd), checked against core/dynamics.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "client/client_fixture.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::ClientError;
using client::Mode;

TEST(ClientModes, LocalShmAndDdsGiveIdenticalResults) {
  SharedServer& shared = SharedServer::get();
  TestServer& server = shared.server();
  Client shm(server.options(Mode::Shm));
  Client dds(server.options(Mode::Dds));
  Client local(server.options(Mode::Local));
  Client automatic(server.options(Mode::Auto));
  EXPECT_EQ(shm.mode(), Mode::Shm);
  EXPECT_EQ(dds.mode(), Mode::Dds);
  EXPECT_EQ(local.mode(), Mode::Local);
  EXPECT_EQ(automatic.mode(), Mode::Local);

  std::vector<client::Function> functions;
  for (Client* c : {&local, &shm, &dds, &automatic}) {
    const client::ModelInfo m = c->loadModel(arm7Text());
    EXPECT_EQ(m.nq, 7);
    EXPECT_EQ(m.nv, 7);
    EXPECT_EQ(m.joint_names, shared.model().jointNames());
    functions.push_back(c->function(m, kRneaJacobianSpec));
    EXPECT_EQ(functions.back().id(), shared.function_id);
    EXPECT_EQ(functions.back().inputCount(), 21u);
    EXPECT_EQ(functions.back().outputCount(), 7u + 147u);
  }
  EXPECT_EQ(functions[0].mode(), Mode::Local);
  EXPECT_EQ(functions[1].mode(), Mode::Shm);
  EXPECT_EQ(functions[2].mode(), Mode::Dds);
  EXPECT_EQ(functions[3].mode(), Mode::Local);
  ASSERT_EQ(functions[0].layout().outputs.size(), 2u);
  EXPECT_EQ(functions[0].layout().outputs[1].cols, 21u);

  for (std::uint64_t seed = 0; seed < 6; ++seed) {
    const RneaReference ref = RneaReference::at(shared.model(), seed);
    std::vector<std::vector<double>> outs;
    for (const client::Function& f : functions) {
      outs.push_back(outputsFor(f));
      const Status s = f.evaluate(spanOf(ref.inputs), outs.back());
      ASSERT_TRUE(s.ok()) << client::toString(f.mode()) << ": " << toString(s.code) << ": " << s.message;
    }
    EXPECT_TRUE(ref.matches(outs[0])) << seed;
    for (std::size_t k = 1; k < outs.size(); ++k)
      for (std::size_t i = 0; i < outs[0].size(); ++i)  // bit-identical: the same library
        ASSERT_EQ(std::memcmp(&outs[0][i], &outs[k][i], sizeof(double)), 0)
            << "function " << k << " (" << client::toString(functions[k].mode()) << ") output " << i << ": "
            << outs[k][i] << " vs local " << outs[0][i];
  }

  // Batches: knots one after another, the same as single calls, in every mode.
  constexpr std::size_t kKnots = 5;
  std::vector<double> ins;
  for (std::size_t k = 0; k < kKnots; ++k) {
    const RneaReference r = RneaReference::at(shared.model(), 50 + k);
    ins.insert(ins.end(), r.inputs.data(), r.inputs.data() + r.inputs.size());
  }
  std::vector<double> local_batch(kKnots * 154), remote_batch(kKnots * 154);
  ASSERT_TRUE(functions[0].evaluateBatch(kKnots, ins, local_batch).ok());
  ASSERT_TRUE(functions[1].evaluateBatch(kKnots, ins, remote_batch).ok());
  for (std::size_t k = 0; k < kKnots; ++k) {
    const RneaReference r = RneaReference::at(shared.model(), 50 + k);
    EXPECT_TRUE(r.matches({local_batch.begin() + k * 154, local_batch.begin() + (k + 1) * 154})) << k;
    EXPECT_TRUE(r.matches({remote_batch.begin() + k * 154, remote_batch.begin() + (k + 1) * 154})) << k;
  }

  // The Eigen convenience and the asynchronous call.
  const RneaReference ref = RneaReference::at(shared.model(), 77);
  for (const client::Function& f : functions) {
    const client::Outputs o = f({ref.inputs.segment(0, 7), ref.inputs.segment(7, 7), ref.inputs.segment(14, 7)});
    ASSERT_EQ(o.blocks.size(), 2u);
    EXPECT_TRUE(o[0].col(0).isApprox(ref.tau, 1e-9));
    EXPECT_EQ(o[1].rows(), 7);
    EXPECT_EQ(o[1].cols(), 21);
    EXPECT_TRUE(o[1].isApprox(ref.jacobian, 1e-5)) << client::toString(f.mode());
    std::vector<double> out = outputsFor(f);
    std::future<Status> done = f.evaluateAsync(spanOf(ref.inputs), out);
    ASSERT_TRUE(done.get().ok());
    EXPECT_TRUE(ref.matches(out));
  }
  EXPECT_THROW(functions[0]({ref.inputs}), ClientError);
}

TEST(ClientModes, EveryModeAnswersWrongInputsWithTheSameStatus) {
  SharedServer& shared = SharedServer::get();
  TestServer& server = shared.server();
  std::vector<Client> clients;
  for (Mode mode : {Mode::Local, Mode::Shm, Mode::Dds}) clients.emplace_back(server.options(mode));
  std::vector<client::Function> functions;
  for (Client& c : clients) functions.push_back(c.function(c.loadModel(arm7Text()), kRneaJacobianSpec));
  ASSERT_EQ(functions[0].mode(), Mode::Local);
  const RneaReference ref = RneaReference::at(shared.model(), 3);

  auto statuses = [&](const Eigen::VectorXd& in, std::size_t out_size) {
    std::vector<Status> s;
    for (const client::Function& f : functions) {
      std::vector<double> out(out_size);
      s.push_back(f.evaluate(spanOf(in), out));
    }
    return s;
  };
  Eigen::VectorXd nan_input = ref.inputs;
  nan_input[9] = std::numeric_limits<double>::quiet_NaN();  // v[2]
  Eigen::VectorXd inf_input = ref.inputs;
  inf_input[20] = -std::numeric_limits<double>::infinity();  // a[6]
  for (const auto& [in, out_size] : std::vector<std::pair<Eigen::VectorXd, std::size_t>>{
           {ref.inputs.head(20), 154}, {ref.inputs, 150}, {nan_input, 154}, {inf_input, 154}}) {
    const std::vector<Status> s = statuses(in, out_size);
    EXPECT_EQ(s[0].code, StatusCode::InvalidArgument) << s[0].message;
    for (std::size_t k = 1; k < s.size(); ++k) {
      EXPECT_EQ(s[k].code, s[0].code) << k << ": " << s[k].message;
      EXPECT_EQ(s[k].message, s[0].message) << k;
    }
  }
  EXPECT_NE(statuses(nan_input, 154)[0].message.find("input v[2] is NaN"), std::string::npos);
  EXPECT_NE(statuses(ref.inputs.head(20), 154)[0].message.find("expected 21"), std::string::npos);
}

TEST(ClientModes, LocalWithoutAServerUsesTheCache) {
  SharedServer& shared = SharedServer::get();
  client::ClientOptions options = shared.server().options(Mode::Local);
  options.server.shm_service = "robodiff-nobody-" + std::to_string(::getpid());
  options.server.dds_domain = emptyTestDomain();  // no server there
  Client local(options);
  EXPECT_EQ(local.mode(), Mode::Local);
  const client::ModelInfo m = local.loadModel(arm7Text());
  client::Function f = local.function(m, kRneaJacobianSpec);
  EXPECT_EQ(f.id(), shared.function_id) << "the same id as the server's";
  EXPECT_EQ(f.mode(), Mode::Local);
  const RneaReference ref = RneaReference::at(shared.model(), 21);
  std::vector<double> out = outputsFor(f);
  ASSERT_TRUE(f.evaluate(spanOf(ref.inputs), out).ok());
  EXPECT_TRUE(ref.matches(out));

  // Not built: the user is told what to do.
  try {
    local.function(m, R"({"function": "rnea", "outputs": [{"kind": "value"}], "build": {"optimization": "O0", "march_native": false}})");
    ADD_FAILURE() << "no library for this spec is cached";
  } catch (const ClientError& e) {
    EXPECT_EQ(e.status().code, StatusCode::FailedPrecondition) << e.what();
    EXPECT_NE(e.status().message.find("robodiff warmup"), std::string::npos) << e.what();
  }
  EXPECT_THROW(local.health(), ClientError);
  EXPECT_THROW(local.fleetStatus(), ClientError);
}

// FleetStatus over either transport: the test server is in no fleet.
TEST(ClientModes, FleetStatusComesFromTheServer) {
  SharedServer& shared = SharedServer::get();
  for (Mode mode : {Mode::Shm, Mode::Dds}) {
    Client c(shared.server().options(mode));
    const rpc::FleetStatusReply reply = c.fleetStatus();
    EXPECT_EQ(reply.fleet.role, "standalone") << client::toString(mode);
    EXPECT_TRUE(reply.fleet.peers.empty()) << client::toString(mode);
  }
}

// A host without the build host's compiler (a robot that imported the library): the full
// key cannot be computed, the portable key finds the library.
TEST(ClientModes, LocalWithoutACompilerFindsTheLibraryByItsPortableKey) {
  SharedServer& shared = SharedServer::get();
  client::ClientOptions options = shared.server().options(Mode::Local);
  options.server.shm_service = "robodiff-nobody-" + std::to_string(::getpid());
  options.server.dds_domain = emptyTestDomain();  // no server there
  const char* cc = std::getenv("CC");
  const std::string saved = cc ? cc : "";
  ::setenv("CC", "/nonexistent/cc", 1);
  Client local(options);
  const client::ModelInfo m = local.loadModel(arm7Text());
  client::Function f = local.function(m, kRneaJacobianSpec);
  if (cc) ::setenv("CC", saved.c_str(), 1);
  else ::unsetenv("CC");
  EXPECT_EQ(f.mode(), Mode::Local);
  const RneaReference ref = RneaReference::at(shared.model(), 22);
  std::vector<double> out = outputsFor(f);
  ASSERT_TRUE(f.evaluate(spanOf(ref.inputs), out).ok());
  EXPECT_TRUE(ref.matches(out));
}

TEST(ClientModes, AnInsistedModeThatCannotBeReachedIsUnavailable) {
  SharedServer& shared = SharedServer::get();
  auto expectUnavailable = [](client::ClientOptions options, const std::string& mentions) {
    try {
      Client c(options);
      ADD_FAILURE() << client::toString(options.server.mode) << " should not connect";
    } catch (const ClientError& e) {
      EXPECT_EQ(e.status().code, StatusCode::Unavailable) << e.what();
      EXPECT_NE(e.status().message.find(mentions), std::string::npos) << e.what();
    }
  };
  client::ClientOptions shm = shared.server().options(Mode::Shm, std::chrono::milliseconds(300));
  shm.server.shm_service = "robodiff-nobody";
  expectUnavailable(shm, "robodiff-nobody");
  client::ClientOptions dds = shared.server().options(Mode::Dds, std::chrono::milliseconds(300));
  dds.server.dds_domain = emptyTestDomain();
  expectUnavailable(dds, "domain " + std::to_string(dds.server.dds_domain));
  client::ClientOptions local = shared.server().options(Mode::Local);
  local.cache_dir = "/nonexistent/robodiff-cache";
  expectUnavailable(local, "/nonexistent/robodiff-cache");
}

}  // namespace
}  // namespace robodiff::testing
