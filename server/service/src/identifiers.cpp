#include "identifiers.hpp"

#include <unistd.h>

#include <cstdio>
#include <random>

#include "robodiff/model/canonical.hpp"

namespace robodiff::server::detail {

std::string makeInstanceId() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0 || host[0] == '\0') std::snprintf(host, sizeof host, "localhost");
  std::random_device random;
  const unsigned nonce = static_cast<unsigned>(random());
  char tail[32];
  std::snprintf(tail, sizeof tail, ":%ld:%08x", static_cast<long>(::getpid()), nonce);
  return std::string(host) + tail;
}

std::string functionId(std::string_view model_id, std::string_view normalized_spec) {
  std::string text;
  text.reserve(model_id.size() + 1 + normalized_spec.size());
  text.append(model_id).append("\n").append(normalized_spec);
  return sha256Hex(text).substr(0, 32);
}

}  // namespace robodiff::server::detail
