// The cache holds code that will be executed, so who may write to it matters: it is
// created 0700, and nothing is loaded from a directory or file that another user could
// have written.
#pragma once

#include <filesystem>

namespace robodiff::cache::detail {

// Creates `dir` (and missing parents) with mode 0700 when it does not exist, then
// checks it: a directory, owned by this user (or root), not writable by group or
// others, writable by its owner. Throws CacheError(Permissions) naming the path, its
// mode and the fix.
void preparePrivateDirectory(const std::filesystem::path& dir, bool create);

// Checks that a file or directory about to be loaded is owned by this user (or root) and
// not writable by group or others. Throws CacheError(Permissions).
void checkNotWritableByOthers(const std::filesystem::path& path);

// "0755"-style text of a mode.
std::string modeText(unsigned mode);

}  // namespace robodiff::cache::detail
