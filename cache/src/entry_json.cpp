// cache::Entry -> JSON (entry_json.hpp).
#include "robodiff/cache/entry_json.hpp"

namespace robodiff::cache {
namespace {

// A JSON text from the index as JSON (a string when it does not parse; null when empty).
nlohmann::json embeddedJson(const std::string& text) {
  if (text.empty()) return nullptr;
  nlohmann::json parsed = nlohmann::json::parse(text, nullptr, false);
  return parsed.is_discarded() ? nlohmann::json(text) : parsed;
}

}  // namespace

nlohmann::json entryJson(const Entry& e) {
  return {{"key", e.key},
          {"robot", e.info.robot},
          {"function", e.info.function},
          {"state", e.state},
          {"model_hash", e.info.model_hash},
          {"spec", embeddedJson(e.info.spec)},
          {"sizes", embeddedJson(e.info.sizes)},
          {"compiler", e.info.compiler},
          {"build_seconds", e.info.build_seconds},
          {"library_bytes", e.library_bytes},
          {"total_bytes", e.total_bytes},
          {"library_sha256", e.library_sha256},
          {"created", e.created},
          {"last_used", e.last_used},
          {"hits", e.hits},
          {"owner", e.owner},
          {"lease_expires_ms", e.lease_expires_ms}};
}

}  // namespace robodiff::cache
