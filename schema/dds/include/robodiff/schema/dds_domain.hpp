#pragma once
// The Cyclone DDS domain robodiff's participants join. With CYCLONEDDS_URI unset, both
// sides use an embedded configuration that keeps DDS on this host (loopback, unicast
// discovery: deploy/cyclonedds-loopback.xml's settings), so that an unconfigured
// robodiffd never serves other hosts and an unconfigured client finds it. Reaching other
// hosts is opt-in: a CYCLONEDDS_URI naming their interfaces, and DDS Security.
#include <cstdint>

namespace robodiff::dds_codec {

// True when CYCLONEDDS_URI is unset or empty (the embedded loopback configuration applies).
bool usesEmbeddedLoopbackConfig();

// The domain id to create a participant on: `domain_id` (kDefaultDomain: Cyclone's default,
// 0), with the embedded configuration created for it first when usesEmbeddedLoopbackConfig().
std::uint32_t prepareDomain(std::uint32_t domain_id);

}  // namespace robodiff::dds_codec
