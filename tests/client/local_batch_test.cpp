// Local evaluateBatch runs through the library's batched entry point (RD_W knots in SIMD
// lanes): the same values as single calls for every remainder of the batch width, and
// the same bits as calling the batched entry point directly and as the server's
// EvaluateBatch (which calls it too), and the batched entry's scratch in use.
// Allocation: hot_path_test.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <thread>

#include "../../client/api/src/thread_buffers.hpp"  // the per-thread scratch, looked at below
#include "client/client_fixture.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/cache/prepared_build.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/model/canonical.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;

constexpr std::size_t kKnotCounts[] = {1, 7, 8, 9, 20, 1000};

// The knots one single evaluate() at a time.
std::vector<double> oneByOne(const client::Function& f, std::size_t knots, const std::vector<double>& in) {
  const std::size_t in_n = f.inputCount(), out_n = f.outputCount();
  std::vector<double> out(knots * out_n, std::nan(""));
  for (std::size_t k = 0; k < knots; ++k) {
    const Status s = f.evaluate({in.data() + k * in_n, in_n}, {out.data() + k * out_n, out_n});
    EXPECT_TRUE(s.ok()) << s.message;
  }
  return out;
}

std::vector<double> batchOf(const client::Function& f, std::size_t knots, const std::vector<double>& in) {
  std::vector<double> out(knots * f.outputCount(), std::nan(""));
  const Status s = f.evaluateBatch(knots, in, out);
  EXPECT_TRUE(s.ok()) << toString(s.code) << ": " << s.message;
  return out;
}

// The library's batched entry point called here: the knots regrouped block after block
// (abi.h), and the outputs back knot after knot.
std::vector<double> directBatch(const codegen::CompiledFunction& fn, const rpc::GetFunctionReply& layout,
                                std::size_t knots, const std::vector<double>& in) {
  std::size_t in_n = 0, out_n = 0;
  for (const rpc::InputBlock& b : layout.inputs) in_n += b.size;
  for (const rpc::OutputBlock& b : layout.outputs) out_n += b.nnz;
  std::vector<double> grouped_in(in.size()), grouped_out(knots * out_n), out(knots * out_n);
  std::vector<const double*> ip;
  std::vector<double*> op;
  for (std::size_t b = 0, offset = 0; b < layout.inputs.size(); offset += layout.inputs[b++].size) {
    const std::size_t size = layout.inputs[b].size;
    ip.push_back(grouped_in.data() + knots * offset);
    for (std::size_t k = 0; k < knots; ++k)
      std::copy_n(in.data() + k * in_n + offset, size, grouped_in.data() + knots * offset + k * size);
  }
  for (std::size_t b = 0, offset = 0; b < layout.outputs.size(); offset += layout.outputs[b++].nnz)
    op.push_back(grouped_out.data() + knots * offset);
  std::vector<double> work(fn.batchWorkSize() + 1);
  fn.evaluateBatch(knots, ip.data(), op.data(), work.data());
  for (std::size_t b = 0, offset = 0; b < layout.outputs.size(); offset += layout.outputs[b++].nnz)
    for (std::size_t k = 0; k < knots; ++k)
      std::copy_n(op[b] + k * layout.outputs[b].nnz, layout.outputs[b].nnz, out.data() + k * out_n + offset);
  return out;
}

std::size_t bitDifferences(const std::vector<double>& a, const std::vector<double>& b) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(double)) != 0 ? 1 : 0;
  return n;
}

TEST(ClientLocalBatch, EqualsSingleCallsForEveryRemainder) {
  SharedServer& shared = SharedServer::get();
  Client local(shared.server().options(Mode::Local));
  const client::Function f = local.function(local.loadModel(arm7Text()), kRneaJacobianSpec);
  ASSERT_EQ(f.mode(), Mode::Local);
  for (const std::size_t knots : kKnotCounts) {
    const std::vector<double> in = randomRneaKnots(shared.model(), knots, 1000 * knots);
    const std::vector<double> batch = batchOf(f, knots, in), single = oneByOne(f, knots, in);
    ASSERT_EQ(batch.size(), single.size());
    // Within 1e-12 relative: the batched code is compiled apart from the single one, and
    // gcc may fuse a multiply-add in one and not the other (-march=native).
    for (std::size_t i = 0; i < batch.size(); ++i)
      ASSERT_LE(std::abs(batch[i] - single[i]), 1e-12 * std::max(std::abs(batch[i]), std::abs(single[i])))
          << knots << " knots: knot " << i / f.outputCount() << " output " << i % f.outputCount() << ": "
          << batch[i] << " vs " << single[i];
    std::printf("%zu knots: %zu of %zu values differ from single calls in the last bits\n", knots,
                bitDifferences(batch, single), batch.size());
  }
  // No knots: nothing to do, and fine.
  EXPECT_TRUE(f.evaluateBatch(0, {}, {}).ok());
}

TEST(ClientLocalBatch, GoesThroughTheLibrarysBatchedEntryPoint) {
  SharedServer& shared = SharedServer::get();
  Client local(shared.server().options(Mode::Local));
  const client::Function f = local.function(local.loadModel(arm7Text()), kRneaJacobianSpec);
  ASSERT_EQ(f.mode(), Mode::Local);
  Client shm(shared.server().options(Mode::Shm));
  const client::Function remote = shm.function(shm.loadModel(arm7Text()), kRneaJacobianSpec);

  // The same library, loaded here: it has a batched entry point of several lanes.
  const std::string key = cache::prepareBuild(shared.model(), canonicalHash(shared.model()), parseFunctionSpec(kRneaJacobianSpec), "", "").key;
  cache::Cache cache = cache::Cache::open(shared.server().cacheDir());
  const std::optional<cache::Artifact> artifact = cache.find(key);
  ASSERT_TRUE(artifact.has_value());
  const codegen::LoadedLibrary library = codegen::LoadedLibrary::open(artifact->library());
  const codegen::CompiledFunction direct = library.function("rnea");
  ASSERT_NE(direct.descriptor().eval_batch, nullptr);
  if (direct.batchWidth() <= 1) GTEST_SKIP() << "a library of batch width 1: its batched entry is a plain loop";

  std::size_t differing = 0, values = 0;
  for (const std::size_t knots : kKnotCounts) {
    const std::vector<double> in = randomRneaKnots(shared.model(), knots, 7 + 1000 * knots);
    const std::vector<double> batched = directBatch(direct, f.layout(), knots, in);
    EXPECT_EQ(bitDifferences(batchOf(f, knots, in), batched), 0u) << knots << " knots: local vs the batched entry";
    EXPECT_EQ(bitDifferences(batchOf(remote, knots, in), batched), 0u)
        << knots << " knots: the server vs the batched entry";
    differing += bitDifferences(oneByOne(f, knots, in), batched);
    values += batched.size();
  }
  // Where the two entry points differ in some bit, the bit-identity above tells them apart.
  std::printf("batch width %u: %zu of %zu values differ between the single and batched entry points%s\n",
              direct.batchWidth(), differing, values,
              differing == 0 ? " (bit-identical here: the values cannot tell which one ran)" : "");
  RecordProperty("entry_points_differing_values", std::to_string(differing));

  // What tells them apart whatever the values: the per-thread scratch. In a fresh thread,
  // a batch regroups its knots block after block (arm7 RNEA has three input blocks) and
  // sizes the work buffer for the batched entry; single calls do neither.
  auto scratchAfter = [&](bool batched) {
    std::size_t regrouped = 0, work = 0;
    std::thread([&] {
      const client::detail::ThreadBuffers& t = client::detail::threadBuffers();
      EXPECT_TRUE(t.batch_in.empty() && t.work.empty());
      const std::vector<double> in = randomRneaKnots(shared.model(), 9, 99);
      if (batched) batchOf(f, 9, in);
      else oneByOne(f, 9, in);
      regrouped = t.batch_in.size();
      work = t.work.size();
    }).join();
    return std::make_pair(regrouped, work);
  };
  const auto [batch_regrouped, batch_work] = scratchAfter(true);
  const auto [single_regrouped, single_work] = scratchAfter(false);
  EXPECT_GE(batch_regrouped, 9 * f.inputCount());
  EXPECT_GE(batch_work, direct.batchWorkSize());
  EXPECT_EQ(single_regrouped, 0u);
  EXPECT_EQ(single_work, direct.workSize());
}

}  // namespace
}  // namespace robodiff::testing
