// Signed entry manifests: canonical text, parsing with checks, and verifying what was
// received against one (entry_manifest.hpp).
#include "robodiff/cache/entry_manifest.hpp"

#include <cctype>
#include <set>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "robodiff/cache/cache_key.hpp"

namespace robodiff::cache {

namespace {

using nlohmann::json;

constexpr int kManifestFormat = 1;
constexpr std::size_t kMaxNameLength = 200;

bool isHex(const std::string& s, std::size_t length) {
  if (s.size() != length) return false;
  for (const char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c)) && (c < 'a' || c > 'f')) return false;
  return true;
}

bool plainFileName(const std::string& name) {
  if (name.empty() || name.size() > kMaxNameLength || name[0] == '.') return false;
  for (const char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-' && c != '+') return false;
  return true;
}

template <typename T>
T field(const json& j, const char* name, const char* where) {
  const auto it = j.find(name);
  if (it == j.end()) throw std::runtime_error(std::string(where) + ": field \"" + name + "\" is missing");
  try {
    return it->get<T>();
  } catch (const json::exception&) {
    throw std::runtime_error(std::string(where) + ": field \"" + name + "\" has the wrong type");
  }
}

std::string shortHex(const std::string& s) { return s.substr(0, 12) + "..."; }

}  // namespace

bool isEntryFileName(const std::string& name) {
  if (name == "library.so" || name == "description.json") return true;
  return name.rfind("src/", 0) == 0 && plainFileName(name.substr(4));
}

std::string manifestText(const EntryManifest& m) {
  json files = json::array();
  for (const ManifestFile& f : m.files) files.push_back({{"name", f.name}, {"size", f.size}, {"sha256", f.sha256}});
  json entry = {{"model_hash", m.info.model_hash}, {"robot", m.info.robot},   {"function", m.info.function},
                {"spec", m.info.spec},             {"sizes", m.info.sizes},   {"compiler", m.info.compiler},
                {"build_seconds", m.info.build_seconds}};
  // Signed with the rest; absent for entries that have none (older ones).
  if (!m.info.portable_key.empty()) entry["portable_key"] = m.info.portable_key;
  const json j = {{"format", kManifestFormat}, {"key", m.key},       {"entry", entry},
                  {"files", files},            {"signer", m.signer}, {"signed_at", m.signed_at}};
  return j.dump();  // nlohmann's objects keep their keys sorted: canonical and compact
}

EntryManifest parseManifest(const std::string& text) {
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw std::runtime_error("manifest.json is not a JSON object");
  if (const int format = field<int>(j, "format", "manifest.json"); format != kManifestFormat)
    throw std::runtime_error("manifest.json has format " + std::to_string(format) + ", this robodiff reads format " +
                             std::to_string(kManifestFormat));
  EntryManifest m;
  m.key = field<std::string>(j, "key", "manifest.json");
  if (!isCacheKey(m.key)) throw std::runtime_error("manifest.json: \"" + m.key + "\" is not a cache key");
  m.signer = field<std::string>(j, "signer", "manifest.json");
  m.signed_at = field<std::int64_t>(j, "signed_at", "manifest.json");
  const json entry = field<json>(j, "entry", "manifest.json");
  if (!entry.is_object()) throw std::runtime_error("manifest.json: \"entry\" is not an object");
  m.info.model_hash = field<std::string>(entry, "model_hash", "manifest.json entry");
  m.info.robot = field<std::string>(entry, "robot", "manifest.json entry");
  m.info.function = field<std::string>(entry, "function", "manifest.json entry");
  m.info.spec = field<std::string>(entry, "spec", "manifest.json entry");
  m.info.sizes = field<std::string>(entry, "sizes", "manifest.json entry");
  m.info.compiler = field<std::string>(entry, "compiler", "manifest.json entry");
  m.info.build_seconds = field<double>(entry, "build_seconds", "manifest.json entry");
  if (entry.contains("portable_key")) m.info.portable_key = field<std::string>(entry, "portable_key", "manifest.json entry");
  const json files = field<json>(j, "files", "manifest.json");
  if (!files.is_array()) throw std::runtime_error("manifest.json: \"files\" is not an array");
  std::set<std::string> seen;
  for (const json& f : files) {
    if (!f.is_object()) throw std::runtime_error("manifest.json: a file is not an object");
    ManifestFile file{field<std::string>(f, "name", "manifest.json file"), field<std::uint64_t>(f, "size", "manifest.json file"),
                      field<std::string>(f, "sha256", "manifest.json file")};
    if (!isEntryFileName(file.name))
      throw std::runtime_error("manifest.json names the file \"" + file.name + "\", which is not an entry file name");
    if (!isHex(file.sha256, 64))
      throw std::runtime_error("manifest.json: the SHA-256 of " + file.name + " is not 64 lowercase hex digits");
    if (!seen.insert(file.name).second) throw std::runtime_error("manifest.json lists " + file.name + " twice");
    m.files.push_back(std::move(file));
  }
  for (const char* required : {"library.so", "description.json"})
    if (!seen.count(required)) throw std::runtime_error(std::string("manifest.json lists no ") + required);
  return m;
}

ManifestCheck verifySignedManifest(const std::string& manifest, const std::string& signature_hex,
                                   const TrustedKeys& trusted) {
  std::string hex = signature_hex;
  while (!hex.empty() && (hex.back() == '\n' || hex.back() == '\r')) hex.pop_back();
  if (!isHex(hex, 128)) return {std::nullopt, "bad signature: manifest.sig is not 128 lowercase hex digits"};
  // The signer's id is read before the signature is checked only to choose the key.
  const json j = json::parse(manifest, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("signer") || !j["signer"].is_string())
    return {std::nullopt, "bad signature: manifest.json is not a signed manifest (no signer)"};
  const std::string signer = j["signer"];
  const PublicKey* key = trusted.find(signer);
  if (key == nullptr) return {std::nullopt, "unknown key: signed by key " + signer + ", which is not trusted here"};
  if (!key->verify(manifest, fromHex(hex)))
    return {std::nullopt, "bad signature: manifest.json's signature does not verify with key " + signer +
                              " (the manifest or its signature was altered)"};
  try {
    return {parseManifest(manifest), ""};
  } catch (const std::exception& e) {
    return {std::nullopt, std::string("malformed manifest (signed by ") + signer + "): " + e.what()};
  }
}

namespace {

// The trusted, parsed manifest of `entry`, or the reason it is not one.
ManifestCheck checkSignature(const ReceivedEntry& entry, const TrustedKeys& trusted) {
  if (!entry.manifest) return {std::nullopt, "unsigned: it has no manifest.json"};
  if (!entry.signature) return {std::nullopt, "unsigned: it has no manifest.sig"};
  return verifySignedManifest(*entry.manifest, *entry.signature, trusted);
}

}  // namespace

ManifestCheck verifyReceivedEntry(const ReceivedEntry& entry, const TrustedKeys& trusted) {
  ManifestCheck check = checkSignature(entry, trusted);
  if (!check.manifest) return check;
  const EntryManifest& m = *check.manifest;
  const auto refuse = [&](std::string problem) { return ManifestCheck{std::nullopt, std::move(problem)}; };
  if (m.key != entry.key)
    return refuse("swapped: the signed manifest is for entry " + m.key + ", but it arrived as entry " + entry.key);
  for (const auto& [name, file] : entry.files) {
    bool listed = false;
    for (const ManifestFile& f : m.files) listed = listed || f.name == name;
    if (!listed) return refuse("extra file " + name + ", not in the signed manifest");
  }
  for (const ManifestFile& f : m.files) {
    const auto it = entry.files.find(f.name);
    if (it == entry.files.end()) return refuse("missing file " + f.name + " (listed in the signed manifest)");
    if (it->second.size != f.size)
      return refuse(f.name + " has " + std::to_string(it->second.size) + " bytes, the signed manifest says " +
                    std::to_string(f.size) + " (truncated or replaced)");
    if (it->second.sha256 != f.sha256)
      return refuse(f.name + ": SHA-256 mismatch (signed " + shortHex(f.sha256) + ", received " +
                    shortHex(it->second.sha256) + ")");
  }
  return check;
}

}  // namespace robodiff::cache
