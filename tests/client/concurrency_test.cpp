// Many controllers at once: 4 threads of this process sharing Clients and Functions of
// every mode, and a second client process, each doing a fixed number of calls with
// every result checked.
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <thread>

#include "client/client_fixture.hpp"

extern char** environ;

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;

constexpr int kCallsPerThread = 300;

// Calls `f` kCalls times over the references, counting good and bad answers.
void hammer(const std::vector<const client::Function*>& functions, const std::vector<RneaReference>& refs, int calls,
            int salt, std::atomic<int>& good, std::atomic<int>& bad, std::string& first_problem) {
  std::vector<double> out(154);
  for (int i = 0; i < calls; ++i) {
    const client::Function& f = *functions[(i + salt) % functions.size()];
    const RneaReference& r = refs[(i * 7 + salt) % refs.size()];
    std::fill(out.begin(), out.end(), std::nan(""));
    const Status s = f.evaluate(spanOf(r.inputs), out);
    if (s.ok() && r.matches(out)) {
      ++good;
    } else {
      if (bad++ == 0)
        first_problem = std::string(client::toString(f.mode())) + ": " + toString(s.code) + ": " + s.message;
    }
  }
}

std::vector<RneaReference> references(const Model& model) {
  std::vector<RneaReference> refs;
  for (int k = 0; k < 8; ++k) refs.push_back(RneaReference::at(model, 300 + k));
  return refs;
}

// The second process: run by ThreadsAndASecondProcess (this executable again, this test
// only); skipped otherwise.
TEST(ClientConcurrency, ChildProcess) {
  const char* cache = std::getenv("ROBODIFF_CLIENT_TEST_CHILD_CACHE");
  if (cache == nullptr) GTEST_SKIP() << "run by ThreadsAndASecondProcess";
  signal(SIGTERM, SIG_IGN);
  client::ClientOptions options = clientOptions(Mode::Auto, cache);
  options.server.shm_service = std::getenv("ROBODIFF_CLIENT_TEST_CHILD_SERVICE");
  options.server.dds_domain = std::atoi(std::getenv("ROBODIFF_CLIENT_TEST_CHILD_DOMAIN"));
  const Model model = loadUrdfString(arm7Text());
  const std::vector<RneaReference> refs = references(model);
  std::vector<Client> clients;
  for (Mode mode : {Mode::Auto, Mode::Shm, Mode::Dds}) {
    options.server.mode = mode;
    clients.emplace_back(options);
  }
  std::vector<client::Function> functions;
  for (Client& c : clients) functions.push_back(c.function(c.loadModel(arm7Text()), kRneaJacobianSpec));
  EXPECT_EQ(functions[0].mode(), Mode::Local);
  std::vector<const client::Function*> all;
  for (const client::Function& f : functions) all.push_back(&f);
  std::atomic<int> good{0}, bad{0};
  std::string problem;
  hammer(all, refs, 3 * kCallsPerThread, 0, good, bad, problem);
  EXPECT_EQ(good.load(), 3 * kCallsPerThread);
  EXPECT_EQ(bad.load(), 0) << problem;
}

TEST(ClientConcurrency, ThreadsAndASecondProcess) {
  SharedServer& shared = SharedServer::get();
  TestServer& server = shared.server();

  // The second client process: this executable, running ChildProcess only.
  const std::string exe = std::filesystem::read_symlink("/proc/self/exe").string();
  std::vector<std::string> args = {exe, "--gtest_filter=ClientConcurrency.ChildProcess"};
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) env.emplace_back(*e);
  env.push_back("ROBODIFF_CLIENT_TEST_CHILD_CACHE=" + server.cacheDir().string());
  env.push_back("ROBODIFF_CLIENT_TEST_CHILD_SERVICE=" + server.service());
  env.push_back("ROBODIFF_CLIENT_TEST_CHILD_DOMAIN=" + std::to_string(testDomain()));
  std::vector<char*> argv, envp;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  for (std::string& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);
  const std::filesystem::path child_log = server.cacheDir().parent_path() / "child.log";
  const pid_t child = fork();
  if (child == 0) {
    const int fd = ::open(child_log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd >= 0) {
      dup2(fd, STDOUT_FILENO);
      dup2(fd, STDERR_FILENO);
    }
    signal(SIGTERM, SIG_DFL);
    execve(argv[0], argv.data(), envp.data());
    _exit(127);
  }
  ASSERT_GT(child, 0);

  const std::vector<RneaReference> refs = references(shared.model());
  Client local(server.options(Mode::Local));
  Client shm(server.options(Mode::Shm));
  Client dds(server.options(Mode::Dds));
  const client::Function fl = local.function(local.loadModel(arm7Text()), kRneaJacobianSpec);
  const client::Function fs = shm.function(shm.loadModel(arm7Text()), kRneaJacobianSpec);
  const client::Function fd = dds.function(dds.loadModel(arm7Text()), kRneaJacobianSpec);
  ASSERT_EQ(fl.mode(), Mode::Local);
  const std::vector<const client::Function*> all = {&fl, &fs, &fd};
  std::atomic<int> good{0}, bad{0};
  std::vector<std::string> problems(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] { hammer(all, refs, kCallsPerThread, t, good, bad, problems[t]); });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(good.load(), 4 * kCallsPerThread);
  EXPECT_EQ(bad.load(), 0) << problems[0] << problems[1] << problems[2] << problems[3];

  int status = 0;
  ASSERT_TRUE(waitFor([&] { return waitpid(child, &status, WNOHANG) == child; }, std::chrono::seconds(60)))
      << readFile(child_log);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the second process:\n" << readFile(child_log);
  const std::string child_output = readFile(child_log);
  EXPECT_NE(child_output.find("[  PASSED  ] 1 test"), std::string::npos) << child_output;
}

}  // namespace
}  // namespace robodiff::testing
