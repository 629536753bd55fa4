// ListFunctions is paged: a page holds at most rpc::kMaxListFunctionsPage functions (or
// the page_size asked for), next_page_token leads to the next, and
// client::listAllFunctions follows the tokens to the whole list.
#include "robodiff/client/connection.hpp"
#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

// RNEA with the acceleration fixed at a value of its own: one distinct function per i.
std::string rneaSpec(int i) {
  return R"({"function": "rnea", "inputs": {"a": {"fixed": [)" + std::to_string(i) +
         R"(, 0, 0, 0, 0, 0, 0]}}, "outputs": [{"kind": "value"}]})";
}

// A client Connection that calls a Service in this process (ListFunctions only).
class InProcessConnection final : public client::Connection {
 public:
  explicit InProcessConnection(Service& service) : service_(service) {}
  std::string_view transport() const override { return "inproc"; }
  // Only ListFunctions is served; every other method is refused.
  Status call(const client::UnaryCall& unary, client::CallOptions) override {
    const auto* list = std::get_if<client::ListFunctionsCall>(&unary);
    if (list == nullptr) return no();
    ++calls;
    return service_.listFunctions(context(), *list->request, *list->reply);
  }
  Status evaluate(std::string_view, std::span<const double>, std::span<double>, client::CallOptions) override {
    return no();
  }
  Status evaluateBatch(std::string_view, std::uint64_t, std::span<const double>, std::span<double>,
                       client::CallOptions) override {
    return no();
  }
  int calls = 0;

 private:
  static Status no() { return {StatusCode::Unimplemented, "not in this test"}; }
  Service& service_;
};

TEST(ListFunctionsPaging, PagesAreCappedAndTheClientGetsTheWholeList) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  const int count = static_cast<int>(rpc::kMaxListFunctionsPage) + 30;
  std::vector<std::string> ids;
  for (int i = 0; i < count; ++i) {
    rpc::GetFunctionReply reply;
    const Status status = getFunction(*service, model_id, rneaSpec(i), false, reply);
    ASSERT_TRUE(status.ok()) << i << ": " << status.message;
    ids.push_back(reply.function_id);
  }

  // One call: a full page, the total, and a token for the rest.
  rpc::ListFunctionsReply first;
  rpc::ListFunctionsRequest request;
  request.page_size = 100000;  // more than the server gives
  ASSERT_TRUE(service->listFunctions(context(), request, first).ok());
  EXPECT_EQ(first.functions.size(), rpc::kMaxListFunctionsPage);
  EXPECT_EQ(first.total, static_cast<std::uint32_t>(count));
  ASSERT_FALSE(first.next_page_token.empty());
  request.page_token = first.next_page_token;
  rpc::ListFunctionsReply second;
  ASSERT_TRUE(service->listFunctions(context(), request, second).ok());
  EXPECT_EQ(second.functions.size(), 30u);
  EXPECT_TRUE(second.next_page_token.empty());
  EXPECT_EQ(second.functions.front().function_id, ids[rpc::kMaxListFunctionsPage]);

  // The client library follows the tokens: every function once, in order of creation.
  InProcessConnection connection(*service);
  std::vector<rpc::FunctionSummary> all;
  rpc::ListFunctionsRequest small_pages;
  small_pages.page_size = 64;
  ASSERT_TRUE(client::listAllFunctions(connection, small_pages, all).ok());
  EXPECT_EQ(connection.calls, (count + 63) / 64);
  ASSERT_EQ(all.size(), ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) EXPECT_EQ(all[i].function_id, ids[i]) << i;
  connection.calls = 0;
  ASSERT_TRUE(client::listAllFunctions(connection, {}, all).ok());
  EXPECT_EQ(connection.calls, 2);
  EXPECT_EQ(all.size(), ids.size());
}

TEST(ListFunctionsPaging, ReleasedFunctionsShiftNoOtherToAnotherPage) {
  ServiceWorkspace ws;
  auto service = ws.start(ws.options());
  const std::string model_id = loadModel(*service, arm7Urdf()).model_id;
  std::vector<std::string> ids;
  for (int i = 0; i < 6; ++i) ids.push_back(readyFunction(*service, model_id, rneaSpec(i)).function_id);
  rpc::ListFunctionsRequest request;
  request.page_size = 3;
  rpc::ListFunctionsReply page;
  ASSERT_TRUE(service->listFunctions(context(), request, page).ok());
  ASSERT_EQ(page.functions.size(), 3u);
  // Released between pages: the next page still starts where the first ended.
  rpc::ReleaseReply released;
  ASSERT_TRUE(service->release(context(), {ids[0]}, released).ok());
  ASSERT_TRUE(service->release(context(), {ids[1]}, released).ok());
  request.page_token = page.next_page_token;
  ASSERT_TRUE(service->listFunctions(context(), request, page).ok());
  ASSERT_EQ(page.functions.size(), 3u);
  EXPECT_EQ(page.functions[0].function_id, ids[3]);
  EXPECT_TRUE(page.next_page_token.empty());
  // A token that is not one is refused, quoted short.
  request.page_token = std::string(5000, 'z');
  const Status status = service->listFunctions(context(), request, page);
  EXPECT_EQ(status.code, StatusCode::InvalidArgument);
  EXPECT_LT(status.message.size(), 300u) << status.message;
}

}  // namespace
}  // namespace robodiff::server::testing
