#include "entry_sidecar.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace robodiff::cache::detail {

namespace {

constexpr int kFormat = 1;

template <typename T>
T field(const nlohmann::json& j, const char* name, const std::filesystem::path& file) {
  const auto it = j.find(name);
  if (it == j.end()) throw std::runtime_error(file.string() + ": field \"" + name + "\" is missing");
  try {
    return it->get<T>();
  } catch (const nlohmann::json::exception&) {
    throw std::runtime_error(file.string() + ": field \"" + name + "\" has the wrong type");
  }
}

}  // namespace

std::string sidecarText(const Entry& e) {
  const nlohmann::json j = {{"format", kFormat},
                            {"key", e.key},
                            {"model_hash", e.info.model_hash},
                            {"robot", e.info.robot},
                            {"function", e.info.function},
                            {"spec", e.info.spec},
                            {"sizes", e.info.sizes},
                            {"compiler", e.info.compiler},
                            {"portable_key", e.info.portable_key},
                            {"build_seconds", e.info.build_seconds},
                            {"library_bytes", e.library_bytes},
                            {"library_sha256", e.library_sha256},
                            {"created", e.created}};
  return j.dump(2) + "\n";
}

Entry readSidecar(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + " is missing or unreadable");
  std::ostringstream text;
  text << in.rdbuf();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(file.string() + " is not valid JSON: " + e.what());
  }
  if (!j.is_object()) throw std::runtime_error(file.string() + " is not a JSON object");
  if (const int format = field<int>(j, "format", file); format != kFormat)
    throw std::runtime_error(file.string() + ": format " + std::to_string(format) + " is not known (expected " +
                             std::to_string(kFormat) + ")");
  Entry e;
  e.key = field<std::string>(j, "key", file);
  e.state = "ready";
  e.info.model_hash = field<std::string>(j, "model_hash", file);
  e.info.robot = field<std::string>(j, "robot", file);
  e.info.function = field<std::string>(j, "function", file);
  e.info.spec = field<std::string>(j, "spec", file);
  e.info.sizes = field<std::string>(j, "sizes", file);
  e.info.compiler = field<std::string>(j, "compiler", file);
  e.info.build_seconds = field<double>(j, "build_seconds", file);
  // Absent from entries written before it was recorded.
  if (const auto it = j.find("portable_key"); it != j.end() && it->is_string()) e.info.portable_key = it->get<std::string>();
  e.library_bytes = field<std::uint64_t>(j, "library_bytes", file);
  e.library_sha256 = field<std::string>(j, "library_sha256", file);
  e.created = field<std::int64_t>(j, "created", file);
  e.last_used = e.created;
  return e;
}

}  // namespace robodiff::cache::detail
