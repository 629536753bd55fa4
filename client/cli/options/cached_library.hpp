// compute's generated backend through the content-addressed cache: the library of
// (robot, spec) is found by the key `warmup` and robodiffd use (cache::prepareBuild),
// its SHA-256 checked by cache::Cache::find (a missing or corrupt library is moved to
// quarantine and rebuilt, never loaded), and built when missing by a robodiff-worker
// process through workers::CachedBuilder (one build per key across every process
// sharing the cache). The loaded function is checked against the index and against the
// function traced here before it is called.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "options/function_backends.hpp"
#include "robodiff/cache/cache.hpp"
#include "robodiff/codegen/loaded_library.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::cli {

// Where the library comes from: the cache directory, the compiler, and the robot and spec
// as the worker reads them (the URDF's text, the file it came from for messages).
struct CachedLibraryRequest {
  std::filesystem::path cache_dir;
  std::string compiler;  // empty: $CC, else cc
  std::string urdf_text, urdf_source;
  bool floating_base = false;
};

class CachedLibrary {
 public:
  // The library of `f` (traced from `model` and f.spec()) from the cache, built there first
  // when missing; `on_building` is called before a build starts (it takes seconds).
  // Throws cache::CacheError (an unusable cache directory, named), std::runtime_error (a
  // build that failed: the worker's message, the compiler's first lines included),
  // codegen::LoadError (a library that does not match the function).
  static CachedLibrary open(const Model& model, const SpecFunction& f, const CachedLibraryRequest& request,
                            const std::function<void()>& on_building = {});

  bool hit() const { return hit_; }  // found in the cache; false: built by this call
  const std::string& key() const { return artifact_.key(); }

  // As SpecFunction::evaluate(Backend::Generated, runtime), by the cached library.
  std::vector<Eigen::MatrixXd> evaluate(const SpecFunction& f, const std::vector<Eigen::VectorXd>& runtime) const;

 private:
  CachedLibrary(cache::Artifact artifact, codegen::CompiledFunction function, bool hit)
      : artifact_(std::move(artifact)), function_(std::move(function)), hit_(hit) {}

  cache::Artifact artifact_;  // pinned: not evicted while loaded
  codegen::CompiledFunction function_;
  bool hit_;
};

}  // namespace robodiff::cli
