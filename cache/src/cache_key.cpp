#include "robodiff/cache/cache_key.hpp"

#include <sys/utsname.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "robodiff/codegen/c_emitter.hpp"
#include "robodiff/model/canonical.hpp"

namespace robodiff::cache {

namespace {

// One "field=value" line. Values may contain anything but newlines are escaped, so one
// field cannot imitate another.
void identityLine(std::ostringstream& s, const char* field, const std::string& value) {
  s << field << '=';
  for (char c : value) {
    if (c == '\n') s << "\\n";
    else if (c == '\\') s << "\\\\";
    else s << c;
  }
  s << '\n';
}

// The identity's text, with or without the compiler line.
std::string identityText(const BuildIdentity& id, bool with_compiler) {
  std::ostringstream s;
  identityLine(s, "format", with_compiler ? "robodiff-cache-key 1" : "robodiff-portable-key 1");
  identityLine(s, "model", id.model_hash);
  identityLine(s, "spec", id.spec);
  identityLine(s, "generator", id.generator);
  if (with_compiler) identityLine(s, "compiler", id.compiler);
  std::string joined;
  for (const std::string& f : id.flags) joined += f + '\x1f';
  identityLine(s, "flags", joined);
  identityLine(s, "target", id.target_cpu);
  return s.str();
}

}  // namespace

std::string BuildIdentity::canonicalText() const { return identityText(*this, true); }
std::string BuildIdentity::key() const { return sha256Hex(canonicalText()); }
std::string BuildIdentity::portableText() const { return identityText(*this, false); }
std::string BuildIdentity::portableKey() const { return sha256Hex(portableText()); }

namespace {

std::string machineArchitecture() {
  utsname u{};
  if (uname(&u) != 0) return "unknown";
  return u.machine;
}

// The first value of `field` in /proc/cpuinfo ("vendor_id", "model name", "flags"...).
std::string cpuinfoField(const std::string& text, const std::string& field) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string name = line.substr(0, colon);
    while (!name.empty() && (name.back() == ' ' || name.back() == '\t')) name.pop_back();
    if (name != field) continue;
    std::string value = line.substr(colon + 1);
    value.erase(0, value.find_first_not_of(' '));
    return value;
  }
  return {};
}

}  // namespace

std::string targetCpuIdentity(bool native, const std::string& level) {
  const std::string arch = machineArchitecture();
  if (!level.empty()) return arch + " " + level;
  if (!native) return arch + " generic";
  std::ifstream f("/proc/cpuinfo");
  std::stringstream text;
  text << f.rdbuf();
  const std::string t = text.str();
  // Flags are sorted: their order in /proc/cpuinfo is not a property of the CPU.
  std::istringstream flag_stream(cpuinfoField(t, "flags").empty() ? cpuinfoField(t, "Features")
                                                                   : cpuinfoField(t, "flags"));
  std::vector<std::string> flags;
  for (std::string w; flag_stream >> w;) flags.push_back(w);
  std::sort(flags.begin(), flags.end());
  std::string joined;
  for (const std::string& w : flags) joined += (joined.empty() ? "" : " ") + w;
  // The instruction cache's size decides which functions are addressed compactly.
  return arch + " native; vendor " + cpuinfoField(t, "vendor_id") + "; family " + cpuinfoField(t, "cpu family") +
         "; model " + cpuinfoField(t, "model") + " (" + cpuinfoField(t, "model name") + "); l1i " +
         std::to_string(codegen::hostInstructionCacheBytes()) + " bytes; flags " + joined;
}

std::string targetLabel(bool native, const std::string& level) {
  if (!level.empty()) return level;
  if (!native) return "generic";
  static const std::string label = "native:" + sha256Hex(targetCpuIdentity(true)).substr(0, 16);
  return label;
}

bool isCacheKey(const std::string& text) {
  return text.size() == 64 &&
         std::all_of(text.begin(), text.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

}  // namespace robodiff::cache
