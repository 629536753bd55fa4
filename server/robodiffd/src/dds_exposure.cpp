// Reading the interfaces out of a Cyclone XML configuration: a light scan for the
// <NetworkInterface .../> elements (and the older <NetworkInterfaceAddress>), no full parse.
#include "dds_exposure.hpp"

#include <fstream>
#include <regex>
#include <sstream>
#include <vector>

namespace robodiff::server {

namespace {

// The XML texts of a CYCLONEDDS_URI: each comma-separated part a file:// URI or inline XML.
std::vector<std::string> configTexts(const std::string& uri) {
  std::vector<std::string> texts;
  std::size_t start = 0;
  while (start <= uri.size()) {
    std::size_t end = uri.find(',', start);
    if (end == std::string::npos) end = uri.size();
    std::string part = uri.substr(start, end - start);
    start = end + 1;
    if (part.rfind("file://", 0) == 0) {
      std::ifstream in(part.substr(7));
      std::stringstream text;
      text << in.rdbuf();
      texts.push_back(text.str());
    } else if (part.find('<') != std::string::npos) {
      texts.push_back(part);
    }
  }
  return texts;
}

bool loopbackAddress(const std::string& address) { return address.rfind("127.", 0) == 0 || address == "::1"; }

// "attr" of one element's attribute text, or "".
std::string attribute(const std::string& attributes, const std::string& name) {
  const std::regex pattern("\\b" + name + R"(\s*=\s*["']([^"']*)["'])");
  std::smatch match;
  return std::regex_search(attributes, match, pattern) ? match[1].str() : std::string();
}

}  // namespace

std::vector<CycloneInterface> cycloneInterfaces(const char* uri) {
  std::vector<CycloneInterface> found;
  if (uri == nullptr) return found;
  static const std::regex element(R"(<NetworkInterface\b([^>]*)>)");
  static const std::regex legacy(R"(<NetworkInterfaceAddress>\s*([^<\s]*)\s*</NetworkInterfaceAddress>)");
  static const std::regex comment(R"(<!--[\s\S]*?-->)");
  for (const std::string& raw : configTexts(uri)) {
    const std::string text = std::regex_replace(raw, comment, "");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), element); it != std::sregex_iterator(); ++it) {
      const std::string attributes = (*it)[1].str();
      found.push_back({attribute(attributes, "name"), attribute(attributes, "address"),
                       attribute(attributes, "autodetermine") == "true"});
    }
    for (auto it = std::sregex_iterator(text.begin(), text.end(), legacy); it != std::sregex_iterator(); ++it) {
      const std::string value = (*it)[1].str();  // an address, or (older configurations) a device name
      found.push_back(value == "lo" ? CycloneInterface{"lo", "", false} : CycloneInterface{"", value, false});
    }
  }
  return found;
}

bool cycloneLoopbackOnly(const char* uri) {
  if (uri == nullptr || *uri == '\0') return true;  // robodiff's embedded loopback configuration
  const std::vector<CycloneInterface> interfaces = cycloneInterfaces(uri);
  for (const CycloneInterface& i : interfaces)
    if (i.autodetermine || (!loopbackAddress(i.address) && i.name != "lo")) return false;
  return !interfaces.empty();
}

std::optional<std::string> ddsExposureRefusal(const DdsExposure& e) {
  if (e.secure || e.loopback_only || e.allow_unauthenticated) return std::nullopt;
  return "DDS would be open (no DDS Security) and reachable from other hosts: CYCLONEDDS_URI does not restrict "
         "Cyclone to loopback interfaces. Set dds.security to a keystore (`robodiff security init`, "
         "deploy/security.md), or use deploy/cyclonedds-loopback.xml, or set dds.allow_unauthenticated = true "
         "to serve open DDS on purpose";
}

}  // namespace robodiff::server
