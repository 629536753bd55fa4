// ListFunctions over every page: the whole list, however many functions the server has.
#include <set>

#include "robodiff/client/connection.hpp"

namespace robodiff::client {

Status listAllFunctions(Connection& connection, const rpc::ListFunctionsRequest& request,
                        std::vector<rpc::FunctionSummary>& functions, CallOptions options) {
  functions.clear();
  rpc::ListFunctionsRequest page_request = request;
  std::set<std::string> tokens_seen;  // a server repeating a token must not loop us forever
  for (;;) {
    rpc::ListFunctionsReply page;
    if (Status s = connection.listFunctions(page_request, page, options); !s.ok()) return s;
    for (rpc::FunctionSummary& f : page.functions) functions.push_back(std::move(f));
    if (page.next_page_token.empty()) return {};
    if (!tokens_seen.insert(page.next_page_token).second)
      return {StatusCode::Internal, "ListFunctions: the server sent the same next_page_token twice"};
    page_request.page_token = std::move(page.next_page_token);
  }
}

}  // namespace robodiff::client
