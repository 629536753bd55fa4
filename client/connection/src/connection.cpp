// What every client connection shares: its default identity.
#include "robodiff/client/connection.hpp"

#include <unistd.h>

#include <cstdio>
#include <random>

namespace robodiff::client {

std::string defaultClientId() {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) std::snprintf(host, sizeof host, "unknown-host");
  std::random_device random;
  char id[320];
  std::snprintf(id, sizeof id, "%s:%d:%08x", host, static_cast<int>(getpid()), static_cast<unsigned>(random()));
  return id;
}

}  // namespace robodiff::client
