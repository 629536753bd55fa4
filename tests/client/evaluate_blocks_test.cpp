// Function::evaluateBlocks: knots whose blocks each live in their own array (numpy's
// layout), handed to the library as they are in Local mode and packed for a server. The
// same bits as evaluate / evaluateBatch on the same knots in every mode; bad inputs get
// evaluate's refusal.
#include <cmath>
#include <cstring>

#include "client/client_fixture.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;

// Knots held block after block: blocks[b] holds block b of every knot, knot after knot.
struct BlockArrays {
  std::vector<std::vector<double>> blocks;
  std::vector<const double*> pointers() const {
    std::vector<const double*> p;
    for (const auto& b : blocks) p.push_back(b.data());
    return p;
  }
};

// Splits knot-major values (a knot's blocks concatenated, knot after knot) into blocks.
BlockArrays splitIntoBlocks(const std::vector<double>& packed, const std::vector<std::size_t>& sizes, std::size_t knots) {
  std::size_t per_knot = 0;
  for (std::size_t s : sizes) per_knot += s;
  BlockArrays a;
  for (std::size_t b = 0, offset = 0; b < sizes.size(); offset += sizes[b++]) {
    a.blocks.emplace_back(knots * sizes[b]);
    for (std::size_t k = 0; k < knots; ++k)
      std::memcpy(a.blocks[b].data() + k * sizes[b], packed.data() + k * per_knot + offset, sizes[b] * sizeof(double));
  }
  return a;
}

std::vector<std::size_t> inputBlockSizes(const client::Function& f) {
  std::vector<std::size_t> sizes;
  for (const rpc::InputBlock& b : f.layout().inputs) sizes.push_back(b.size);
  return sizes;
}

std::vector<std::size_t> outputBlockSizes(const client::Function& f) {
  std::vector<std::size_t> sizes;
  for (const rpc::OutputBlock& b : f.layout().outputs) sizes.push_back(b.nnz);
  return sizes;
}

// evaluateBlocks on `knots` knots against evaluateBatch (batch) or evaluate (one knot):
// every output bit equal.
void expectSameBits(const client::Function& f, const Model& model, std::size_t knots, bool batch) {
  const std::vector<double> in = randomRneaKnots(model, knots, 31 * knots + 5);
  std::vector<double> want(knots * f.outputCount(), std::nan(""));
  const Status w = batch ? f.evaluateBatch(knots, in, want) : f.evaluate(in, want);
  ASSERT_TRUE(w.ok()) << w.message;
  const BlockArrays inputs = splitIntoBlocks(in, inputBlockSizes(f), knots);
  BlockArrays outputs = splitIntoBlocks(std::vector<double>(want.size(), std::nan("")), outputBlockSizes(f), knots);
  std::vector<double*> out;
  for (auto& b : outputs.blocks) out.push_back(b.data());
  const std::vector<const double*> ip = inputs.pointers();
  const Status s = f.evaluateBlocks(knots, ip, out, batch);
  ASSERT_TRUE(s.ok()) << toString(s.code) << ": " << s.message;
  const BlockArrays expected = splitIntoBlocks(want, outputBlockSizes(f), knots);
  for (std::size_t b = 0; b < expected.blocks.size(); ++b)
    EXPECT_EQ(std::memcmp(expected.blocks[b].data(), outputs.blocks[b].data(), expected.blocks[b].size() * sizeof(double)), 0)
        << toString(f.mode()) << ", " << knots << " knots, output block " << b;
}

TEST(ClientEvaluateBlocks, SameBitsAsPackedCallsInEveryMode) {
  SharedServer& shared = SharedServer::get();
  for (const Mode mode : {Mode::Local, Mode::Shm, Mode::Dds}) {
    Client c(shared.server().options(mode));
    const client::Function f = c.function(c.loadModel(arm7Text()), kRneaJacobianSpec);
    ASSERT_EQ(f.mode(), mode);
    expectSameBits(f, shared.model(), 1, false);
    for (const std::size_t knots : {1, 7, 9, 100}) expectSameBits(f, shared.model(), knots, true);
  }
}

TEST(ClientEvaluateBlocks, ANaNInputIsRefusedAsEvaluateRefusesIt) {
  SharedServer& shared = SharedServer::get();
  Client local(shared.server().options(Mode::Local));
  const client::Function f = local.function(local.loadModel(arm7Text()), kRneaJacobianSpec);
  ASSERT_EQ(f.mode(), Mode::Local);
  std::vector<double> in = randomRneaKnots(shared.model(), 3, 1);
  in[f.inputCount() + 9] = std::nan("");  // knot 1, the third value of v
  std::vector<double> packed_out(3 * f.outputCount());
  const Status want = f.evaluateBatch(3, in, packed_out);
  ASSERT_EQ(want.code, StatusCode::InvalidArgument);
  const BlockArrays inputs = splitIntoBlocks(in, inputBlockSizes(f), 3);
  BlockArrays outputs = splitIntoBlocks(packed_out, outputBlockSizes(f), 3);
  std::vector<double*> out;
  for (auto& b : outputs.blocks) out.push_back(b.data());
  const std::vector<const double*> ip = inputs.pointers();
  const Status s = f.evaluateBlocks(3, ip, out, true);
  EXPECT_EQ(s.code, StatusCode::InvalidArgument);
  EXPECT_EQ(s.message, want.message);
}

}  // namespace
}  // namespace robodiff::testing
