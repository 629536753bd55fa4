// model_hash: prints the canonical hash (or, with --form, the canonical form) of a URDF.
//
// Built as `model_hash_generic` from core/model's sources compiled a second time for the
// generic x86-64 target (core/model/CMakeLists.txt), so that tests/model/portable_hash_test
// can check that the model's identity does not depend on the -march it was compiled with.
//
//   model_hash_generic [--free-flyer] [--form] robot.urdf
#include <cstdio>
#include <exception>
#include <string>

#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"

int main(int argc, char** argv) {
  robodiff::RootJoint root = robodiff::RootJoint::Fixed;
  bool form = false;
  std::string path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--free-flyer") root = robodiff::RootJoint::FreeFlyer;
    else if (arg == "--form") form = true;
    else if (path.empty() && !arg.empty() && arg[0] != '-') path = arg;
    else {
      std::fprintf(stderr, "model_hash: unexpected argument '%s'\n"
                           "usage: model_hash [--free-flyer] [--form] robot.urdf\n", arg.c_str());
      return 2;
    }
  }
  if (path.empty()) {
    std::fprintf(stderr, "usage: model_hash [--free-flyer] [--form] robot.urdf\n");
    return 2;
  }
  try {
    const robodiff::Model model = robodiff::loadUrdfFile(path, root);
    const std::string text = form ? robodiff::canonicalForm(model) : robodiff::canonicalHash(model) + "\n";
    std::fwrite(text.data(), 1, text.size(), stdout);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "model_hash: %s\n", e.what());
    return 1;
  }
}
