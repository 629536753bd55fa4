// Output blocks as Eigen views over the caller's outputs: a sparse (CSR) Jacobian as a
// row-major Eigen sparse matrix, a dense value as a row-major matrix, both checked against
// core/dynamics and central differences; the wrong layout or index is a clear error.
#include <gtest/gtest.h>

#include "client/client_fixture.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::ClientError;
using client::Mode;

constexpr const char* kSparseRneaJacobianSpec =
    R"({"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"], "layout": "sparse"}],
        "build": {"optimization": "O1", "march_native": false}})";

TEST(ClientBlocks, SparseAndDenseBlocksAsEigenViews) {
  SharedServer& shared = SharedServer::get();
  Client shm(shared.server().options(Mode::Shm));
  const client::Function f = shm.function(shm.loadModel(arm7Text()), kSparseRneaJacobianSpec);
  ASSERT_EQ(f.layout().outputs.at(1).layout, rpc::OutputLayout::SparseCsr);
  const RneaReference ref = RneaReference::at(shared.model(), 21);
  std::vector<double> out(f.outputCount());
  ASSERT_TRUE(f.evaluate(spanOf(ref.inputs), out).ok());

  const client::Function::DenseBlock tau = f.denseBlock(0, out);
  ASSERT_EQ(tau.rows(), 7);
  ASSERT_EQ(tau.cols(), 1);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(tau(i, 0), ref.tau[i], 1e-9 * (1 + std::abs(ref.tau[i])));

  const client::Function::SparseBlock jacobian = f.sparseBlock(1, out);
  ASSERT_EQ(jacobian.rows(), 7);
  ASSERT_EQ(jacobian.cols(), 21);
  EXPECT_EQ(static_cast<std::uint32_t>(jacobian.nonZeros()), f.layout().outputs[1].nnz);
  EXPECT_EQ(jacobian.valuePtr(), out.data() + 7) << "a view, not a copy";
  const Eigen::MatrixXd dense = Eigen::MatrixXd(jacobian);
  EXPECT_LT((dense - ref.jacobian).cwiseAbs().maxCoeff(), 1e-5);
  // The same numbers as the allocating convenience form.
  EXPECT_EQ((dense - f({ref.inputs.head(7), ref.inputs.segment(7, 7), ref.inputs.tail(7)})[1]).cwiseAbs().maxCoeff(),
            0.0);

  auto codeOf = [](auto&& call) {
    try {
      call();
    } catch (const ClientError& e) {
      return e.status().code;
    }
    return StatusCode::Ok;
  };
  EXPECT_EQ(codeOf([&] { f.sparseBlock(0, out); }), StatusCode::InvalidArgument);  // dense block
  EXPECT_EQ(codeOf([&] { f.denseBlock(1, out); }), StatusCode::InvalidArgument);   // sparse block
  EXPECT_EQ(codeOf([&] { f.denseBlock(2, out); }), StatusCode::InvalidArgument);   // no such block
  EXPECT_EQ(codeOf([&] { f.sparseBlock(1, std::span<const double>(out).first(10)); }), StatusCode::InvalidArgument);
}

}  // namespace
}  // namespace robodiff::testing
