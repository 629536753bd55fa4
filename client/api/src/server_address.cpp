// Where the server is, as people write it: on the command line (--server) and in
// $ROBODIFF_SERVER.
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "robodiff/client/client.hpp"

namespace robodiff::client {

const char* toString(Mode mode) {
  switch (mode) {
    case Mode::Auto: return "auto";
    case Mode::Local: return "local";
    case Mode::Shm: return "shm";
    case Mode::Dds: return "dds";
  }
  return "auto";
}

ServerAddress parseServerAddress(std::string_view text) {
  const std::string s(text);
  auto fail = [&]() -> ServerAddress {
    throw std::invalid_argument("server address '" + s +
                                "' is not one of auto, local, shm, shm:<service>, dds, dds:<domain 0-232>");
  };
  ServerAddress address;
  const auto colon = s.find(':');
  const std::string kind = s.substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : s.substr(colon + 1);
  if (kind == "auto" || kind == "local") {
    if (colon != std::string::npos) return fail();
    address.mode = kind == "auto" ? Mode::Auto : Mode::Local;
  } else if (kind == "shm") {
    address.mode = Mode::Shm;
    if (colon != std::string::npos) {
      if (rest.empty() || rest.size() > 100) return fail();
      address.shm_service = rest;
    }
  } else if (kind == "dds") {
    address.mode = Mode::Dds;
    if (colon != std::string::npos) {
      if (rest.empty() || rest.size() > 3 || rest.find_first_not_of("0123456789") != std::string::npos) return fail();
      const int domain = std::stoi(rest);
      if (domain > 232) return fail();
      address.dds_domain = domain;
    }
  } else {
    return fail();
  }
  return address;
}

ServerAddress serverAddressFromEnvironment() {
  const char* env = std::getenv("ROBODIFF_SERVER");
  if (env == nullptr || *env == '\0') return {};
  try {
    return parseServerAddress(env);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("$ROBODIFF_SERVER: ") + e.what());
  }
}

}  // namespace robodiff::client
