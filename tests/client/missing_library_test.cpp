// A library deleted from the cache while no server holds it: a client in Auto mode is
// served by the server (never by a missing or stale file) while the server builds the
// library again, then switches to Local on the rebuilt library with the same answers.
#include <filesystem>

#include "client/client_fixture.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;
using std::chrono::seconds;

std::filesystem::path onlyLibraryIn(const std::filesystem::path& cache_dir) {
  std::vector<std::filesystem::path> found;
  for (const auto& e : std::filesystem::recursive_directory_iterator(cache_dir / "objects"))
    if (e.path().filename() == "library.so") found.push_back(e.path());
  EXPECT_EQ(found.size(), 1u);
  return found.empty() ? std::filesystem::path() : found[0];
}

TEST(ClientCacheHealing, ADeletedLibraryIsRebuiltByTheServerAndUsedLocallyAgain) {
  TestServer server;
  server.start();
  const Model model = loadUrdfString(arm7Text());
  const RneaReference ref = RneaReference::at(model, 17);
  {
    Client first(server.options(Mode::Auto));
    client::Function f = first.function(first.loadModel(arm7Text()), kRneaJacobianSpec);
    ASSERT_TRUE(waitFor([&] { return serverCompiled(first, f.id()); }, seconds(120))) << server.log();
  }
  server.kill();
  const std::filesystem::path library = onlyLibraryIn(server.cacheDir());
  ASSERT_FALSE(library.empty());
  std::filesystem::remove(library);
  server.start();

  Client again(server.options(Mode::Auto));
  client::Function g = again.function(again.loadModel(arm7Text()), kRneaJacobianSpec);
  std::vector<double> out = outputsFor(g);
  ASSERT_TRUE(g.evaluate(spanOf(ref.inputs), out).ok());
  EXPECT_TRUE(ref.matches(out));
  ASSERT_TRUE(waitFor([&] { return serverCompiled(again, g.id()); }, seconds(120))) << server.log();
  EXPECT_TRUE(waitFor([&] {
    EXPECT_TRUE(g.evaluate(spanOf(ref.inputs), out).ok());
    return g.mode() == Mode::Local;
  }, seconds(5)));
  EXPECT_TRUE(ref.matches(out));
  EXPECT_TRUE(std::filesystem::is_regular_file(onlyLibraryIn(server.cacheDir())));
  EXPECT_FALSE(std::filesystem::is_empty(server.cacheDir() / "quarantine"));
}

}  // namespace
}  // namespace robodiff::testing
