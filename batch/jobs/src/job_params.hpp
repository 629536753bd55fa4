#pragma once
// Reading a job's parameters (a JSON object) with errors that name the field.
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/batch_job.hpp"
#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch::params {

// A required string field; JobParamsError when missing or not a string.
std::string requiredString(const nlohmann::json& p, const char* field);
std::optional<std::string> optionalString(const nlohmann::json& p, const char* field);
bool optionalBool(const nlohmann::json& p, const char* field, bool fallback);
double optionalNumber(const nlohmann::json& p, const char* field, double fallback);
// A file that must exist, and lie where `files` allows (the path is on the host running
// the job): the path to open, symbolic links resolved when restricted.
std::filesystem::path existingFile(const nlohmann::json& p, const char* field, const FileAccess& files);
// A plain file name for a result inside the job's directory (no '/', not "." or "..").
std::string resultFileName(const nlohmann::json& p, const char* field, const std::string& fallback);

// "backend": compiled (the default) or interpreted; JobParamsError otherwise.
Backend backend(const nlohmann::json& p);

// The robot: "urdf" (a path) or "urdf_text", and "floating_base".
struct Robot {
  std::string urdf_text, source;
  bool floating_base = false;
  Model model;
};
Robot robot(const nlohmann::json& p, const FileAccess& files);
void checkRobotFields(const nlohmann::json& p, const FileAccess& files);  // without loading it

// The function: "spec" (a path) or "spec_json" (an object or its text).
FunctionSpec spec(const nlohmann::json& p, const FileAccess& files);
void checkSpecFields(const nlohmann::json& p, const FileAccess& files);

}  // namespace robodiff::batch::params
