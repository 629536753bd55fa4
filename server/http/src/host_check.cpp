#include "host_check.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <cctype>

namespace robodiff::server {
namespace {

std::string lowered(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

bool isIpLiteral(const std::string& host) {
  unsigned char buffer[16];
  return inet_pton(AF_INET, host.c_str(), buffer) == 1 || inet_pton(AF_INET6, host.c_str(), buffer) == 1;
}

bool endsWith(const std::string& s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::string hostOfHeader(std::string_view header) {
  if (header.empty()) return {};
  if (header.front() == '[') {  // [v6]:port
    const auto close = header.find(']');
    if (close == std::string_view::npos) return {};
    const std::string_view rest = header.substr(close + 1);
    if (!rest.empty() && rest.front() != ':') return {};
    return lowered(header.substr(1, close - 1));
  }
  const auto colon = header.find(':');
  std::string host = lowered(header.substr(0, colon));
  if (!host.empty() && host.back() == '.') host.pop_back();  // "localhost." is "localhost"
  return host;
}

bool hostAllowed(std::string_view header, const std::vector<std::string>& names) {
  const std::string host = hostOfHeader(header);
  if (host.empty()) return false;
  if (isIpLiteral(host) || host == "localhost" || endsWith(host, ".localhost")) return true;
  return std::any_of(names.begin(), names.end(), [&](const std::string& name) { return lowered(name) == host; });
}

}  // namespace robodiff::server
