#include "job_paths.hpp"

#include <algorithm>
#include <string>

#include "robodiff/batch/batch_job.hpp"

namespace robodiff::batch::params {
namespace {

namespace fs = std::filesystem;

// weakly_canonical: resolves what exists of the path, keeps the rest lexically.
bool resolve(const fs::path& path, fs::path& resolved) {
  std::error_code ec;
  resolved = fs::weakly_canonical(path, ec);
  return !ec;
}

// `path` is `dir` followed by at least one more component.
bool strictlyUnder(const fs::path& path, const fs::path& dir) {
  auto p = path.begin();
  for (auto d = dir.begin(); d != dir.end(); ++d, ++p) {
    if (d->empty()) continue;  // a trailing separator in `dir`
    if (p == path.end() || *p != *d) return false;
  }
  return p != path.end();
}

std::string listed(const std::vector<fs::path>& dirs) {
  if (dirs.empty()) return "none are configured";
  std::string text;
  for (const fs::path& d : dirs) text += (text.empty() ? "" : ", ") + d.string();
  return text;
}

}  // namespace

fs::path pathUnder(const fs::path& given, const std::vector<fs::path>& dirs, const char* field) {
  const std::string where = std::string(field) + ": '" + given.string().substr(0, 200) + "'";
  if (!given.is_absolute())
    throw JobParamsError(where + " must be an absolute path (a service's job does not share your working directory)");
  fs::path resolved;
  if (resolve(given, resolved))
    for (const fs::path& dir : dirs) {
      fs::path resolved_dir;
      if (resolve(dir, resolved_dir) && strictlyUnder(resolved, resolved_dir)) return resolved;
    }
  throw JobParamsError(where + " is outside the directories this service's jobs may read (" + listed(dirs) +
                       "): put the file there (jobs.data_dirs in robodiffd.conf), or send its content inline "
                       "(urdf_text, spec_json)");
}

}  // namespace robodiff::batch::params
