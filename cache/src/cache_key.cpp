#include "robodiff/cache/cache_key.hpp"

#include <sys/utsname.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "robodiff/model/canonical.hpp"

namespace robodiff::cache {

std::string BuildIdentity::canonicalText() const {
  // Values may contain anything but newlines are escaped, so one field cannot imitate
  // another.
  auto line = [](std::ostringstream& s, const char* field, const std::string& value) {
    s << field << '=';
    for (char c : value) {
      if (c == '\n') s << "\\n";
      else if (c == '\\') s << "\\\\";
      else s << c;
    }
    s << '\n';
  };
  std::ostringstream s;
  line(s, "format", "robodiff-cache-key 1");
  line(s, "model", model_hash);
  line(s, "spec", spec);
  line(s, "generator", generator);
  line(s, "compiler", compiler);
  std::string joined;
  for (const std::string& f : flags) joined += f + '\x1f';
  line(s, "flags", joined);
  line(s, "target", target_cpu);
  return s.str();
}

std::string BuildIdentity::key() const { return sha256Hex(canonicalText()); }

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
  return arch + " native; vendor " + cpuinfoField(t, "vendor_id") + "; family " + cpuinfoField(t, "cpu family") +
         "; model " + cpuinfoField(t, "model") + " (" + cpuinfoField(t, "model name") + "); flags " + joined;
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
