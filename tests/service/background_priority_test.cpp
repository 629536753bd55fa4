// The service's request threads run `background_nice` nicer than the thread that made the
// service, so the transports' receive threads (Evaluate) come first on a full CPU
// (thread_priority.hpp; measured with bench/flood_bench).
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <future>

#include "service_fixtures.hpp"

namespace robodiff::server::testing {
namespace {

int niceOfCallingThread() {
  errno = 0;
  return ::getpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)));
}

int niceOfARequestThread(Service& service) {
  std::promise<int> nice;
  EXPECT_TRUE(service.post([&nice] { nice.set_value(niceOfCallingThread()); }));
  return nice.get_future().get();
}

TEST(BackgroundPriority, RequestThreadsRunNicerByTheConfiguredAmount) {
  ServiceWorkspace ws;
  const int own = niceOfCallingThread();
  ServiceOptions options = ws.options();
  options.background_nice = 7;
  auto service = ws.start(options);
  EXPECT_EQ(niceOfARequestThread(*service), std::min(own + 7, 19));
  EXPECT_EQ(niceOfCallingThread(), own) << "the thread that made the service keeps its priority";
}

TEST(BackgroundPriority, ZeroLeavesRequestThreadsAtTheCallersPriority) {
  ServiceWorkspace ws;
  ServiceOptions options = ws.options();
  options.background_nice = 0;
  auto service = ws.start(options);
  EXPECT_EQ(niceOfARequestThread(*service), niceOfCallingThread());
}

TEST(BackgroundPriority, DefaultIsTen) { EXPECT_EQ(ServiceOptions{}.background_nice, 10u); }

}  // namespace
}  // namespace robodiff::server::testing
