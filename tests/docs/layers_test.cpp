// docs/architecture.md's layers hold in the code: a layer folder includes the headers and
// links the libraries of its own layer and of layers below it only. core/ and schema/ are
// at the bottom (schema, the wire types, uses nothing else), then cache, then workers and
// runtime, then batch, then client and server; folders on one level never use each other
// but for one named crossing (serverUsesClientTransport). So workers/ never includes or
// links batch/ (the robodiff-worker program that runs batch jobs is built in batch/jobs).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

namespace fs = std::filesystem;

// Top-level folders and their levels, bottom first.
const std::map<std::string, int>& layerLevels() {
  static const std::map<std::string, int> levels = {{"core", 0},    {"schema", 0}, {"cache", 1},  {"workers", 2},
                                                    {"runtime", 2}, {"batch", 3},  {"client", 4}, {"server", 4}};
  return levels;
}

bool mayUse(const std::string& user, const std::string& used) {
  return user == used || layerLevels().at(used) < layerLevels().at(user);
}

// The one crossing between client and server (docs/architecture.md): a robot host's
// robodiffd calls its build hosts as a DDS client (server/fleet), through the client's
// transport layer only, never its API or CLI.
bool serverUsesClientTransport(const std::string& user, const std::string& name) {
  static const std::vector<std::string> allowed = {"robodiff/client/dds_connection.hpp",
                                                   "robodiff/client/connection.hpp", "robodiff::client_dds",
                                                   "robodiff::client_connection"};
  return user == "server" && std::find(allowed.begin(), allowed.end(), name) != allowed.end();
}

// Who provides what: include directories ("model" of robodiff/model/ -> "core") and CMake
// targets ("robodiff_workers" and its alias "robodiff::workers" -> "workers").
struct LayerMap {
  std::map<std::string, std::string> include_dirs;
  std::map<std::string, std::string> targets;
};

std::string textOf(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// CMake text without its comments (a mention in a comment is no dependency).
std::string cmakeCode(const fs::path& path) {
  std::istringstream in(textOf(path));
  std::string code;
  for (std::string line; std::getline(in, line);) code += line.substr(0, line.find('#')) + "\n";
  return code;
}

// Every file under root/<layer> whose name ends with one of `suffixes`, by layer.
std::vector<std::pair<std::string, fs::path>> layerFiles(const fs::path& root, const std::vector<std::string>& suffixes) {
  std::vector<std::pair<std::string, fs::path>> files;
  for (const auto& [layer, level] : layerLevels()) {
    if (!fs::is_directory(root / layer)) continue;
    for (const fs::directory_entry& e : fs::recursive_directory_iterator(root / layer)) {
      if (!e.is_regular_file()) continue;
      const std::string name = e.path().filename().string();
      for (const std::string& s : suffixes)
        if (name.size() >= s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0)
          files.emplace_back(layer, e.path());
    }
  }
  return files;
}

const std::vector<std::string> kSourceSuffixes = {".cpp", ".hpp", ".h", ".c"};

LayerMap mapLayers(const fs::path& root) {
  LayerMap map;
  for (const auto& [layer, file] : layerFiles(root, kSourceSuffixes)) {
    const fs::path dir = file.parent_path();
    if (dir.parent_path().filename() == "robodiff" && dir.parent_path().parent_path().filename() == "include")
      map.include_dirs[dir.filename().string()] = layer;
  }
  const std::regex defined(R"((robodiff_library|add_library|add_executable)\(\s*([A-Za-z0-9_]+)[\s)])");
  for (const auto& [layer, file] : layerFiles(root, {"CMakeLists.txt"})) {
    const std::string code = cmakeCode(file);
    for (std::sregex_iterator m(code.begin(), code.end(), defined), end; m != end; ++m) {
      const std::string name = (*m)[2].str();
      const bool helper = (*m)[1] == "robodiff_library";  // robodiff_<name> and robodiff::<name>
      map.targets[helper ? "robodiff_" + name : name] = layer;
      if (helper) map.targets["robodiff::" + name] = layer;
    }
  }
  return map;
}

std::string pathInTree(const fs::path& root, const fs::path& file) { return fs::relative(file, root).string(); }

// "workers/src/x.cpp:3 includes robodiff/batch/batch_job.hpp (batch)" for each include of
// a header of a layer the file's own layer may not use; `seen` counts every include found.
std::vector<std::string> upwardIncludes(const fs::path& root, const LayerMap& map, int* seen = nullptr) {
  std::vector<std::string> problems;
  const std::regex include(R"(^\s*#\s*include\s*[<"](robodiff/([A-Za-z0-9_]+)/[^>"]*)[>"])");
  for (const auto& [layer, file] : layerFiles(root, kSourceSuffixes)) {
    std::istringstream in(textOf(file));
    int line_number = 0;
    for (std::string line; std::getline(in, line);) {
      ++line_number;
      std::smatch m;
      if (line.find("include") == std::string::npos || !std::regex_search(line, m, include)) continue;
      const auto provider = map.include_dirs.find(m[2].str());
      if (provider == map.include_dirs.end()) continue;  // not a layer's header
      if (seen) ++*seen;
      if (!mayUse(layer, provider->second) && !serverUsesClientTransport(layer, m[1].str()))
        problems.push_back(pathInTree(root, file) + ":" + std::to_string(line_number) + " includes " + m[1].str() +
                           " (" + provider->second + ")");
    }
  }
  return problems;
}

// "workers/CMakeLists.txt uses robodiff::batch_jobs (batch)" for each target of a layer the
// folder may not use, and each ${CMAKE_SOURCE_DIR}/<layer> path into one.
std::vector<std::string> upwardLinks(const fs::path& root, const LayerMap& map, int* seen = nullptr) {
  std::vector<std::string> problems;
  const std::regex word(R"([A-Za-z_][A-Za-z0-9_]*(::[A-Za-z0-9_]+)?)");
  const std::regex source_path(R"(\$\{CMAKE_SOURCE_DIR\}/([A-Za-z0-9_]+))");
  for (const auto& [layer, file] : layerFiles(root, {"CMakeLists.txt"})) {
    const std::string code = cmakeCode(file);
    std::map<std::string, std::string> used;  // name -> its layer
    for (std::sregex_iterator m(code.begin(), code.end(), word), end; m != end; ++m)
      if (const auto target = map.targets.find(m->str()); target != map.targets.end()) used[m->str()] = target->second;
    for (std::sregex_iterator m(code.begin(), code.end(), source_path), end; m != end; ++m)
      if (layerLevels().count((*m)[1].str())) used["${CMAKE_SOURCE_DIR}/" + (*m)[1].str()] = (*m)[1].str();
    for (const auto& [name, provider] : used) {
      if (seen) ++*seen;
      if (!mayUse(layer, provider) && !serverUsesClientTransport(layer, name)) problems.push_back(pathInTree(root, file) + " uses " + name + " (" + provider + ")");
    }
  }
  return problems;
}

std::string lines(const std::vector<std::string>& items) {
  std::string text;
  for (const std::string& item : items) text += "  " + item + "\n";
  return text;
}

TEST(Architecture, NoLayerIncludesALayerAboveOrBesideIt) {
  const LayerMap map = mapLayers(sourceDir());
  EXPECT_EQ(map.include_dirs.at("model"), "core");
  EXPECT_EQ(map.include_dirs.at("batch"), "batch");
  int seen = 0;
  const std::vector<std::string> problems = upwardIncludes(sourceDir(), map, &seen);
  EXPECT_GT(seen, 300) << "too few includes of robodiff/<layer>/ headers found: is the source tree there?";
  EXPECT_TRUE(problems.empty()) << "includes against docs/architecture.md's layers:\n" << lines(problems);
}

TEST(Architecture, NoLayerLinksALayerAboveOrBesideIt) {
  const LayerMap map = mapLayers(sourceDir());
  EXPECT_EQ(map.targets.at("robodiff::batch_jobs"), "batch");
  EXPECT_EQ(map.targets.at("robodiff_worker"), "batch");  // the worker program runs batch jobs
  int seen = 0;
  const std::vector<std::string> problems = upwardLinks(sourceDir(), map, &seen);
  EXPECT_GT(seen, 50) << "too few uses of robodiff's targets found: is the source tree there?";
  EXPECT_TRUE(problems.empty()) << "CMake uses against docs/architecture.md's layers:\n" << lines(problems);
}

// The checks themselves, on a small tree where workers/ uses batch/ as it once did.
TEST(Architecture, TheChecksFindWorkersUsingBatch) {
  TempDir tree;
  const auto put = [&](const std::string& name, const std::string& text) {
    fs::create_directories((tree / name).parent_path());
    tree.file(name, text);
  };
  put("batch/jobs/include/robodiff/batch/batch_job.hpp", "#pragma once\n");
  put("batch/jobs/CMakeLists.txt", "robodiff_library(batch_jobs src/batch_job.cpp)\n");
  put("workers/include/robodiff/workers/worker_host.hpp", "#pragma once\n");
  put("workers/src/worker_main.cpp",
      "// robodiff/batch/batch_job.hpp, in a comment\n#include \"robodiff/workers/worker_host.hpp\"\n"
      "#include \"robodiff/batch/batch_job.hpp\"\n");
  put("workers/CMakeLists.txt",
      "robodiff_library(workers src/worker_host.cpp)  # robodiff::batch_jobs, in a comment\n"
      "add_executable(robodiff_worker src/worker_main.cpp)\n"
      "target_link_libraries(robodiff_worker PRIVATE robodiff::workers robodiff::batch_jobs)\n"
      "target_include_directories(robodiff_worker PRIVATE ${CMAKE_SOURCE_DIR}/batch/jobs/src)\n");
  const LayerMap map = mapLayers(tree.path());
  EXPECT_EQ(upwardIncludes(tree.path(), map),
            std::vector<std::string>{"workers/src/worker_main.cpp:3 includes robodiff/batch/batch_job.hpp (batch)"});
  EXPECT_EQ(upwardLinks(tree.path(), map),
            (std::vector<std::string>{"workers/CMakeLists.txt uses ${CMAKE_SOURCE_DIR}/batch (batch)",
                                      "workers/CMakeLists.txt uses robodiff::batch_jobs (batch)"}));
  // Beside is not below either: client and server, workers and runtime.
  EXPECT_FALSE(mayUse("client", "server"));
  EXPECT_FALSE(mayUse("workers", "runtime"));
  EXPECT_TRUE(mayUse("server", "batch"));
  // The one crossing is the client's transport, from server/ only.
  EXPECT_TRUE(serverUsesClientTransport("server", "robodiff/client/dds_connection.hpp"));
  EXPECT_FALSE(serverUsesClientTransport("server", "robodiff/client/client.hpp"));
  EXPECT_FALSE(serverUsesClientTransport("server", "robodiff::client"));
  EXPECT_FALSE(serverUsesClientTransport("batch", "robodiff::client_dds"));
}

}  // namespace
}  // namespace robodiff::testing
