#pragma once
// Whether robodiffd's DDS participant can be reached from other hosts, judged from the
// Cyclone configuration (CYCLONEDDS_URI), and the policy that follows: open DDS only on
// loopback unless the operator explicitly allows it (deploy/security.md).

#include <optional>
#include <string>
#include <vector>

namespace robodiff::server {

// True when the Cyclone configuration `uri` (CYCLONEDDS_URI's value: file:// URIs or inline
// XML, comma-separated) names network interfaces and every one of them is loopback
// (address 127.x.x.x or ::1, or name "lo"); also when unset or empty, since robodiff then
// uses its embedded loopback configuration (schema/dds dds_domain.hpp). Autodetermine or
// any other interface: false (Cyclone then uses a network interface).
bool cycloneLoopbackOnly(const char* uri);

// One <NetworkInterface> (or legacy <NetworkInterfaceAddress>) of a Cyclone configuration.
struct CycloneInterface {
  std::string name, address;
  bool autodetermine = false;
};
// Every interface named in `uri`'s configuration texts, comments ignored.
std::vector<CycloneInterface> cycloneInterfaces(const char* uri);

struct DdsExposure {
  bool secure = false;         // a keystore is configured
  bool loopback_only = false;  // cycloneLoopbackOnly(CYCLONEDDS_URI)
  bool allow_unauthenticated = false;
};

// The reason robodiffd must refuse to start (open DDS reaching other hosts without
// allow_unauthenticated), or nothing.
std::optional<std::string> ddsExposureRefusal(const DdsExposure& exposure);

}  // namespace robodiff::server
