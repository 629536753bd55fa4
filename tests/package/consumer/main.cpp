// Uses the installed robodiff client: a server address, a Client on its own (empty)
// cache in local mode, a model loaded locally, and the clear error for a function that
// is not in the cache. Prints what it saw; exits 0 when everything is as expected.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <robodiff/client/client.hpp>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer URDF CACHE_DIR\n");
    return 2;
  }
  using namespace robodiff::client;
  const ServerAddress address = parseServerAddress("dds:7");
  if (address.mode != Mode::Dds || address.dds_domain != 7) return 1;

  std::ifstream in(argv[1]);
  std::stringstream urdf;
  urdf << in.rdbuf();
  ClientOptions options;
  options.server = parseServerAddress("local");
  // Local mode still asks a robodiffd when one answers; this test wants none: a DDS domain
  // no test's server uses (ctest keeps RouDi-starting tests apart from this one).
  options.server.dds_domain = 232;
  options.cache_dir = argv[2];
  Client client(options);
  const ModelInfo model = client.loadModel(urdf.str());
  std::printf("model %s nq %d nv %d\n", model.id.c_str(), model.nq, model.nv);
  try {
    client.function(model, R"({"function": "rnea", "outputs": [{"kind": "value"}]})");
    std::printf("unexpected: a function from an empty cache\n");
    return 1;
  } catch (const ClientError& e) {
    std::printf("function: %s\n", e.what());
    return e.status().code == robodiff::StatusCode::FailedPrecondition && model.nq == 7 ? 0 : 1;
  }
}
