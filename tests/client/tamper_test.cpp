// Local evaluation trusts only a verified library: the cache checks its SHA-256 and
// quarantines a mismatch; the Function then evaluates through the server (Auto) or is
// refused (insisted Local), never with the bad library. Also: an Auto Function served
// by the server while it compiles switches to Local once the library is in the cache.
#include <fstream>
#include <iterator>

#include "client/client_fixture.hpp"

namespace robodiff::testing {
namespace {

using client::Client;
using client::Mode;
using std::chrono::seconds;

// The only library.so under the cache's objects/.
std::filesystem::path onlyLibrary(const std::filesystem::path& cache_dir) {
  std::vector<std::filesystem::path> found;
  for (const auto& e : std::filesystem::recursive_directory_iterator(cache_dir / "objects"))
    if (e.path().filename() == "library.so") found.push_back(e.path());
  EXPECT_EQ(found.size(), 1u);
  return found.empty() ? std::filesystem::path() : found[0];
}

// Flips one byte in the middle of `library`, writing a new file renamed over it (so a
// process that has the library mapped keeps the original), with the same permissions.
void tamper(const std::filesystem::path& library) {
  namespace fs = std::filesystem;
  std::string bytes;
  {
    std::ifstream in(library, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_GT(bytes.size(), 100u);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x01);
  const fs::perms file_perms = fs::status(library).permissions();
  const fs::perms dir_perms = fs::status(library.parent_path()).permissions();
  fs::permissions(library.parent_path(), fs::perms::owner_all, fs::perm_options::add);
  const fs::path temporary = library.parent_path() / "library.so.tampered";
  {
    std::ofstream out(temporary, std::ios::binary);
    out << bytes;
  }
  fs::permissions(temporary, file_perms);
  fs::rename(temporary, library);
  fs::permissions(library.parent_path(), dir_perms);
}

TEST(ClientCacheTrust, AutoSwitchesToLocalOnceCompiledAndRefusesATamperedLibrary) {
  TestServer server;  // a cache of its own: this test spoils it
  server.start();
  const Model model = loadUrdfString(arm7Text());
  const RneaReference ref = RneaReference::at(model, 31);

  // Asked before the library exists: the server serves it (interpreted) meanwhile.
  Client first(server.options(Mode::Auto));
  ASSERT_EQ(first.mode(), Mode::Local);
  client::Function f = first.function(first.loadModel(arm7Text()), kRneaJacobianSpec);
  const Mode initial = f.mode();
  std::vector<double> out = outputsFor(f);
  ASSERT_TRUE(f.evaluate(spanOf(ref.inputs), out).ok());
  EXPECT_TRUE(ref.matches(out));
  ASSERT_TRUE(waitFor([&] { return serverCompiled(first, f.id()); }, seconds(120))) << server.log();
  // Calls switch it to Local (the cache is looked at again at most every 100 ms).
  EXPECT_TRUE(waitFor([&] {
    EXPECT_TRUE(f.evaluate(spanOf(ref.inputs), out).ok());
    return f.mode() == Mode::Local;
  }, seconds(5))) << "initially " << client::toString(initial);
  EXPECT_TRUE(ref.matches(out));
  if (initial == Mode::Local) std::printf("note: the library was compiled before GetFunction answered\n");

  // Spoil the cached library, then clients that load it afresh.
  const std::filesystem::path library = onlyLibrary(server.cacheDir());
  ASSERT_FALSE(library.empty());
  tamper(library);

  Client second(server.options(Mode::Auto));
  client::Function g = second.function(second.loadModel(arm7Text()), kRneaJacobianSpec);
  EXPECT_EQ(g.mode(), Mode::Shm) << "the tampered library must not be used";
  std::vector<double> out2 = outputsFor(g);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(g.evaluate(spanOf(ref.inputs), out2).ok());
    std::this_thread::sleep_for(std::chrono::milliseconds(120));  // past a re-check of the cache
  }
  EXPECT_EQ(g.mode(), Mode::Shm);
  EXPECT_TRUE(ref.matches(out2));
  EXPECT_EQ(out2, out) << "the server's library (loaded before the damage) gives the same bits";
  // The cache moved it to quarantine.
  EXPECT_FALSE(std::filesystem::exists(library));
  EXPECT_FALSE(std::filesystem::is_empty(server.cacheDir() / "quarantine"));

  try {
    Client insisted(server.options(Mode::Local));
    insisted.function(insisted.loadModel(arm7Text()), kRneaJacobianSpec);
    ADD_FAILURE() << "insisted Local must refuse a function whose library failed verification";
  } catch (const client::ClientError& e) {
    EXPECT_EQ(e.status().code, StatusCode::FailedPrecondition) << e.what();
  }
  // The first Function keeps the verified library it loaded.
  EXPECT_EQ(f.mode(), Mode::Local);
  ASSERT_TRUE(f.evaluate(spanOf(ref.inputs), out).ok());
  EXPECT_TRUE(ref.matches(out));
}

}  // namespace
}  // namespace robodiff::testing
