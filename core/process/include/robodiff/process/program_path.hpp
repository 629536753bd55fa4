// Where a program is: a path checked to be an executable file, or a name looked up in PATH.
#pragma once

#include <filesystem>
#include <string>

namespace robodiff::process {

// A regular file this process may execute.
bool isExecutableFile(const std::filesystem::path& path);

// The executable `name` names: itself when it contains '/', else the first match in
// PATH (/usr/local/bin:/usr/bin:/bin when PATH is unset; an empty entry is the current
// directory). Empty when there is none.
std::string findProgram(const std::string& name);

// Why findProgram(name) found nothing, for a message: "'/opt/cc' does not exist",
// "'/opt/cc' is not an executable file", or "'cc' is not in PATH (/usr/bin:/bin)".
std::string whyNotFound(const std::string& name);

}  // namespace robodiff::process
