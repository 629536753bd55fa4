// Asking RouDi's service registry who offers a request/response service.
#include "shm_discovery.hpp"

#include <thread>

#include "iceoryx_posh/runtime/service_discovery.hpp"

namespace robodiff::server {

bool serviceOffered(iox::runtime::ServiceDiscovery& discovery, const iox::capro::ServiceDescription& description) {
  bool found = false;
  discovery.findService(description.getServiceIDString(), description.getInstanceIDString(),
                        description.getEventIDString(), [&](const iox::capro::ServiceDescription&) { found = true; },
                        iox::popo::MessagingPattern::REQ_RES);
  return found;
}

bool waitForServiceFree(const iox::capro::ServiceDescription& description, std::chrono::milliseconds wait) {
  iox::runtime::ServiceDiscovery discovery;
  const auto until = std::chrono::steady_clock::now() + wait;
  while (serviceOffered(discovery, description)) {
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

}  // namespace robodiff::server
