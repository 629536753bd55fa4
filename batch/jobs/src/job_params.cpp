// Job parameters: typed reads with messages naming the field and the value.
#include "job_params.hpp"

#include <fstream>
#include <sstream>

#include "job_paths.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::batch::params {
namespace {

std::string readText(const std::filesystem::path& path, const char* field) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw JobParamsError(std::string(field) + ": cannot read " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

std::optional<std::string> optionalString(const nlohmann::json& p, const char* field) {
  const auto it = p.find(field);
  if (it == p.end() || it->is_null()) return std::nullopt;
  if (!it->is_string()) throw JobParamsError(std::string(field) + " must be a string, not " + it->dump());
  return it->get<std::string>();
}

std::string requiredString(const nlohmann::json& p, const char* field) {
  auto value = optionalString(p, field);
  if (!value || value->empty()) throw JobParamsError(std::string("the job needs \"") + field + "\"");
  return *value;
}

bool optionalBool(const nlohmann::json& p, const char* field, bool fallback) {
  const auto it = p.find(field);
  if (it == p.end() || it->is_null()) return fallback;
  if (!it->is_boolean()) throw JobParamsError(std::string(field) + " must be true or false, not " + it->dump());
  return it->get<bool>();
}

double optionalNumber(const nlohmann::json& p, const char* field, double fallback) {
  const auto it = p.find(field);
  if (it == p.end() || it->is_null()) return fallback;
  if (!it->is_number()) throw JobParamsError(std::string(field) + " must be a number, not " + it->dump());
  return it->get<double>();
}

std::filesystem::path existingFile(const nlohmann::json& p, const char* field, const FileAccess& files) {
  std::filesystem::path path = requiredString(p, field);
  if (files.restricted) path = pathUnder(path, files.readable_dirs, field);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw JobParamsError(std::string(field) + ": no file " + path.string() + " on the host running the job");
  return path;
}

std::string resultFileName(const nlohmann::json& p, const char* field, const std::string& fallback) {
  const std::string name = optionalString(p, field).value_or(fallback);
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos)
    throw JobParamsError(std::string(field) + " '" + name +
                         "' must be a plain file name (the job writes only into its own directory)");
  return name;
}

Backend backend(const nlohmann::json& p) {
  const std::string text = optionalString(p, "backend").value_or("compiled");
  try {
    return parseBackend(text);
  } catch (const std::invalid_argument& e) {
    throw JobParamsError(std::string("backend: ") + e.what());
  }
}

void checkRobotFields(const nlohmann::json& p, const FileAccess& files) {
  if (p.contains("urdf_text")) {
    requiredString(p, "urdf_text");
  } else {
    existingFile(p, "urdf", files);
  }
  optionalBool(p, "floating_base", false);
}

Robot robot(const nlohmann::json& p, const FileAccess& files) {
  checkRobotFields(p, files);
  Robot r;
  r.floating_base = optionalBool(p, "floating_base", false);
  if (p.contains("urdf_text")) {
    r.urdf_text = requiredString(p, "urdf_text");
    r.source = "urdf_text";
  } else {
    r.source = existingFile(p, "urdf", files).string();
    r.urdf_text = readText(r.source, "urdf");
  }
  r.model = loadUrdfString(r.urdf_text, r.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed, r.source);
  return r;
}

void checkSpecFields(const nlohmann::json& p, const FileAccess& files) {
  if (p.contains("spec_json")) {
    const auto& s = p["spec_json"];
    if (!s.is_object() && !s.is_string()) throw JobParamsError("spec_json must be a spec object or its JSON text");
  } else {
    existingFile(p, "spec", files);
  }
}

FunctionSpec spec(const nlohmann::json& p, const FileAccess& files) {
  checkSpecFields(p, files);
  if (p.contains("spec_json")) {
    const auto& s = p["spec_json"];
    return parseFunctionSpec(s.is_string() ? s.get<std::string>() : s.dump(), "spec_json");
  }
  const std::filesystem::path path = existingFile(p, "spec", files);
  return parseFunctionSpec(readText(path, "spec"), path.string());
}

}  // namespace robodiff::batch::params
