// Evaluate and EvaluateBatch on the interpreter (compile off): RNEA and its Jacobian
// against core/dynamics in double and finite differences, a batch against the same knots
// one at a time, and every error: sizes, NaN and infinite inputs, unknown ids, too many
// knots, deadlines; outputs stay untouched on errors.
#include <atomic>
#include <thread>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "robodiff/dynamics/rnea.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

struct Arm7Function {
  ServiceWorkspace ws;
  std::unique_ptr<Service> service;
  rpc::LoadModelReply model;
  rpc::GetFunctionReply function;

  explicit Arm7Function(const char* spec, const std::function<void(ServiceOptions&)>& adjust = {}) {
    ServiceOptions options = ws.options();
    if (adjust) adjust(options);
    service = ws.start(options);
    model = loadModel(*service, arm7Urdf());
    function = readyFunction(*service, model.model_id, spec);
  }
};

Eigen::VectorXd rneaReference(const Model& model, const std::vector<double>& x) {
  const Eigen::Index n = model.nv;
  Data<double> data(model);
  const Eigen::Map<const Eigen::VectorXd> q(x.data(), n), v(x.data() + n, n), a(x.data() + 2 * n, n);
  return rnea(model, data, q, v, a);
}

TEST(Evaluate, RneaValueAndJacobianMatchDynamicsAndFiniteDifferences) {
  Arm7Function f(kRneaJacobianSpec);
  ASSERT_EQ(f.function.inputs.size(), 3u);
  EXPECT_EQ(f.function.inputs[0].name, "q");
  EXPECT_EQ(f.function.inputs[1].name, "v");
  EXPECT_EQ(f.function.inputs[2].name, "a");
  ASSERT_EQ(f.function.outputs.size(), 2u);
  EXPECT_EQ(f.function.outputs[0].kind, rpc::OutputKind::Value);
  EXPECT_EQ(f.function.outputs[1].kind, rpc::OutputKind::Jacobian);
  EXPECT_EQ(f.function.outputs[1].rows, 7u);
  EXPECT_EQ(f.function.outputs[1].cols, 21u);
  EXPECT_EQ(f.function.outputs[1].layout, rpc::OutputLayout::DenseRowMajor);
  ASSERT_EQ(rpc::inputCount(f.function), 21u);
  ASSERT_EQ(rpc::outputCount(f.function), 7u + 7u * 21u);

  const Model model = loadUrdfString(arm7Urdf());
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const std::vector<double> x = someInputs(21, seed);
    const std::vector<double> out = evaluateOnce(*f.service, f.function, x);
    const Eigen::VectorXd tau = rneaReference(model, x);
    for (int i = 0; i < 7; ++i) EXPECT_NEAR(out[i], tau[i], 1e-10 * std::max(1.0, std::fabs(tau[i]))) << "tau " << i;
    // Central differences, column by column.
    const double h = 1e-6;
    for (int c = 0; c < 21; ++c) {
      std::vector<double> plus = x, minus = x;
      plus[c] += h;
      minus[c] -= h;
      const Eigen::VectorXd d = (rneaReference(model, plus) - rneaReference(model, minus)) / (2 * h);
      for (int r = 0; r < 7; ++r)
        EXPECT_NEAR(out[7 + r * 21 + c], d[r], 1e-5 * std::max(1.0, std::fabs(d[r])))
            << "d tau " << r << " / d x " << c;
    }
  }
  EXPECT_EQ(summaryOf(*f.service, f.function.function_id).evaluations, 3u);
  EXPECT_FALSE(summaryOf(*f.service, f.function.function_id).compiled);
}

TEST(Evaluate, ABatchOf1000KnotsEqualsTheKnotsOneByOne) {
  Arm7Function f(kRneaJacobianSpec);
  const std::size_t knots = 1000, in = rpc::inputCount(f.function), out = rpc::outputCount(f.function);
  const std::vector<double> inputs = someInputs(knots * in, 7);
  std::vector<double> batch(knots * out, -1.0);
  const Status status = f.service->evaluateBatch(context(), f.function.function_id, knots, inputs, batch);
  ASSERT_TRUE(status.ok()) << status.message;
  for (std::size_t k = 0; k < knots; ++k) {
    const std::vector<double> x(inputs.begin() + static_cast<long>(k * in),
                                inputs.begin() + static_cast<long>((k + 1) * in));
    const std::vector<double> one = evaluateOnce(*f.service, f.function, x);
    const std::vector<double> from_batch(batch.begin() + static_cast<long>(k * out),
                                         batch.begin() + static_cast<long>((k + 1) * out));
    ASSERT_EQ(from_batch, one) << "knot " << k;
  }
  EXPECT_EQ(summaryOf(*f.service, f.function.function_id).evaluations, 2 * knots);
}

TEST(Evaluate, ConcurrentBatchesShareTheBatchThreadsAndStayExact) {
  Arm7Function f(kRneaJacobianSpec, [](ServiceOptions& o) { o.batch_threads = 3; });
  EXPECT_EQ(health(*f.service).batch_threads, 3u);
  const std::size_t in = rpc::inputCount(f.function), out = rpc::outputCount(f.function);
  const std::vector<std::size_t> sizes = {1, 5, 17, 300, 1001};  // one piece, and many
  std::vector<std::vector<double>> inputs, expected;
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    inputs.push_back(someInputs(sizes[b] * in, 100 + b));
    std::vector<double> one_by_one;
    for (std::size_t k = 0; k < sizes[b]; ++k) {
      const std::vector<double> x(inputs[b].begin() + static_cast<long>(k * in),
                                  inputs[b].begin() + static_cast<long>((k + 1) * in));
      const std::vector<double> y = evaluateOnce(*f.service, f.function, x);
      one_by_one.insert(one_by_one.end(), y.begin(), y.end());
    }
    expected.push_back(std::move(one_by_one));
  }
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int round = 0; round < 10; ++round) {
        const std::size_t b = static_cast<std::size_t>(t + round) % sizes.size();
        std::vector<double> result(sizes[b] * out);
        const Status s = f.service->evaluateBatch(context(), f.function.function_id, sizes[b], inputs[b], result);
        if (!s.ok() || result != expected[b]) ++wrong;
      }
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(wrong.load(), 0);
}

TEST(Evaluate, WrongSizesAreInvalidArgumentNamingBothAndLeaveOutputsAlone) {
  Arm7Function f(kRneaJacobianSpec);
  const std::string& id = f.function.function_id;
  std::vector<double> out(rpc::outputCount(f.function), 7.0);
  Status status = f.service->evaluate(context(), id, someInputs(20, 1), out);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("expected 21"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("given 20"), std::string::npos) << status.message;
  std::vector<double> short_out(out.size() - 1, 7.0);
  status = f.service->evaluate(context(), id, someInputs(21, 1), short_out);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("given " + std::to_string(out.size() - 1)), std::string::npos) << status.message;
  std::vector<double> batch_out(3 * out.size(), 7.0);
  status = f.service->evaluateBatch(context(), id, 3, someInputs(62, 1), batch_out);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("expected 63"), std::string::npos) << status.message;
  for (double v : out) ASSERT_EQ(v, 7.0);
  for (double v : batch_out) ASSERT_EQ(v, 7.0);
}

TEST(Evaluate, NonFiniteInputsNameTheirBlockIndexAndKnot) {
  Arm7Function f(kRneaJacobianSpec);
  const std::string& id = f.function.function_id;
  std::vector<double> x = someInputs(21, 2);
  x[7 + 3] = std::nan("");  // v[3]
  std::vector<double> out(rpc::outputCount(f.function), 7.0);
  Status status = f.service->evaluate(context(), id, x, out);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("v[3]"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("NaN"), std::string::npos) << status.message;
  for (double v : out) ASSERT_EQ(v, 7.0);

  std::vector<double> batch = someInputs(10 * 21, 3);
  batch[5 * 21 + 14 + 6] = -INFINITY;  // knot 5, a[6]
  std::vector<double> batch_out(10 * out.size(), 7.0);
  status = f.service->evaluateBatch(context(), id, 10, batch, batch_out);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_NE(status.message.find("a[6]"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("knot 5"), std::string::npos) << status.message;
  for (double v : batch_out) ASSERT_EQ(v, 7.0);
}

TEST(Evaluate, UnknownIdsAreNotFound) {
  Arm7Function f(kRneaValueSpec);
  std::vector<double> in(21, 0.0), out(7, 0.0);
  Status status = f.service->evaluate(context(), "0123456789abcdef0123456789abcdef", in, out);
  EXPECT_EQ(status.code, StatusCode::NotFound);
  EXPECT_NE(status.message.find("0123456789abcdef0123456789abcdef"), std::string::npos) << status.message;
  EXPECT_EQ(f.service->evaluateBatch(context(), "nope", 1, in, out).code, StatusCode::NotFound);
  FunctionShape shape;
  EXPECT_EQ(f.service->shape("nope", shape).code, StatusCode::NotFound);
  rpc::GetFunctionReply reply;
  EXPECT_EQ(getFunction(*f.service, std::string(64, 'a'), kRneaValueSpec, false, reply).code, StatusCode::NotFound);
  rpc::ListFunctionsReply list;
  EXPECT_EQ(f.service->listFunctions(context(), {std::string(64, 'a'), 0, ""}, list).code, StatusCode::NotFound);
  rpc::ReleaseReply released;
  EXPECT_EQ(f.service->release(context(), {"nope"}, released).code, StatusCode::NotFound);

  ASSERT_TRUE(f.service->shape(f.function.function_id, shape).ok());
  EXPECT_EQ(shape.input_count, 21u);
  EXPECT_EQ(shape.output_count, 7u);
  EXPECT_EQ(shape.max_batch_knots, f.service->options().max_batch_knots);
}

TEST(Evaluate, TooManyKnotsIsResourceExhausted) {
  Arm7Function f(kRneaValueSpec, [](ServiceOptions& o) { o.max_batch_knots = 100; });
  std::vector<double> in(101 * 21, 0.1), out(101 * 7, 7.0);
  const Status status = f.service->evaluateBatch(context(), f.function.function_id, 101, in, out);
  EXPECT_EQ(status.code, StatusCode::ResourceExhausted);
  EXPECT_NE(status.message.find("max_batch_knots"), std::string::npos) << status.message;
  for (double v : out) ASSERT_EQ(v, 7.0);
  in.resize(100 * 21);
  out.resize(100 * 7);
  EXPECT_TRUE(f.service->evaluateBatch(context(), f.function.function_id, 100, in, out).ok());
}

TEST(Evaluate, AnExpiredDeadlineIsDeadlineExceededForEveryMethod) {
  Arm7Function f(kRneaValueSpec);
  const CallContext late = expiredContext();
  std::vector<double> in(21, 0.1), out(7, 7.0);
  EXPECT_EQ(f.service->evaluate(late, f.function.function_id, in, out).code, StatusCode::DeadlineExceeded);
  EXPECT_EQ(f.service->evaluateBatch(late, f.function.function_id, 1, in, out).code, StatusCode::DeadlineExceeded);
  for (double v : out) ASSERT_EQ(v, 7.0);
  rpc::LoadModelRequest load{arm7Urdf(), false, ""};
  rpc::LoadModelReply loaded;
  EXPECT_EQ(f.service->loadModel(late, load, loaded).code, StatusCode::DeadlineExceeded);
  rpc::GetFunctionRequest get{f.model.model_id, kRneaValueSpec, true};
  rpc::GetFunctionReply got;
  EXPECT_EQ(f.service->getFunction(late, get, got).code, StatusCode::DeadlineExceeded);
  rpc::ListFunctionsReply list;
  EXPECT_EQ(f.service->listFunctions(late, {}, list).code, StatusCode::DeadlineExceeded);
  rpc::HealthReply h;
  EXPECT_EQ(f.service->health(late, {}, h).code, StatusCode::DeadlineExceeded);
  rpc::ReleaseReply released;
  EXPECT_EQ(f.service->release(late, {f.function.function_id}, released).code, StatusCode::DeadlineExceeded);
  // Nothing was taken or given back by the late requests.
  EXPECT_EQ(health(*f.service).models_loaded, 1u);
  ASSERT_TRUE(f.service->release(context(), {f.function.function_id}, released).ok());
  EXPECT_EQ(released.references_left, 0u);
}

TEST(Evaluate, ADeadlineThatPassesDuringABatchStopsIt) {
  Arm7Function f(kRneaJacobianSpec);
  const std::uint64_t knots = 50000;
  const std::vector<double> in = someInputs(knots * 21, 4);
  std::vector<double> out(knots * rpc::outputCount(f.function));
  CallContext ctx = context();
  ctx.deadline = Clock::now() + std::chrono::milliseconds(5);
  const Status status = f.service->evaluateBatch(ctx, f.function.function_id, knots, in, out);
  EXPECT_EQ(status.code, StatusCode::DeadlineExceeded) << status.message;
}

}  // namespace
}  // namespace robodiff::server::testing
