#include "robodiff/schema/dds_domain.hpp"

#include <cstdlib>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>

#include "robodiff/schema/dds_topics.hpp"
#include "robodiff.h"

namespace robodiff::dds_codec {
namespace {

// deploy/cyclonedds-loopback.xml without its comments.
constexpr const char* kLoopbackConfig =
    "<CycloneDDS><Domain Id=\"any\">"
    "<General><Interfaces><NetworkInterface name=\"lo\" multicast=\"false\"/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>"
    "<Peers><Peer Address=\"127.0.0.1\"/></Peers></Discovery>"
    "<SharedMemory><Enable>false</Enable></SharedMemory>"
    "</Domain></CycloneDDS>";

}  // namespace

bool usesEmbeddedLoopbackConfig() {
  const char* uri = std::getenv("CYCLONEDDS_URI");
  return uri == nullptr || *uri == '\0';
}

std::uint32_t prepareDomain(std::uint32_t domain_id) {
  if (!usesEmbeddedLoopbackConfig()) return domain_id;
  const std::uint32_t id = domain_id == kDefaultDomain ? 0 : domain_id;
  static std::mutex mutex;
  static std::set<std::uint32_t> created;  // kept for the process's life, as Cyclone's default domain is
  std::lock_guard lock(mutex);
  if (created.count(id) != 0) return id;
  const dds_entity_t domain = dds_create_domain(id, kLoopbackConfig);
  // PRECONDITION_NOT_MET: the domain exists already (made by this process another way).
  if (domain < 0 && domain != DDS_RETCODE_PRECONDITION_NOT_MET)
    throw std::runtime_error(ddsError("dds_create_domain", domain) + " for DDS domain " + std::to_string(id) +
                             " with robodiff's loopback configuration");
  created.insert(id);
  return id;
}

}  // namespace robodiff::dds_codec
