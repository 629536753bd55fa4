#pragma once
// Where a service's job may read: a path checked against the readable directories
// before anything opens it.
#include <filesystem>
#include <vector>

namespace robodiff::batch::params {

// `given` resolved (absolute, symbolic links followed, "." and ".." gone) when it lies
// strictly under one of `dirs` (themselves resolved). Otherwise JobParamsError naming
// `field`, the path as given and the directories, the same whether or not the path
// exists: a caller learns nothing about files outside. Relative paths are refused (the
// job runs in another process's working directory).
std::filesystem::path pathUnder(const std::filesystem::path& given, const std::vector<std::filesystem::path>& dirs,
                                const char* field);

}  // namespace robodiff::batch::params
