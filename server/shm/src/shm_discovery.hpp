#pragma once
// Asking RouDi's service registry who offers a request/response service: robodiffd waits
// for a previous server of its name to go before it offers the service itself.

#include <chrono>

#include "iceoryx_posh/capro/service_description.hpp"

namespace iox::runtime {
class ServiceDiscovery;
}

namespace robodiff::server {

// Whether some process offers `description` as a server (request/response).
bool serviceOffered(iox::runtime::ServiceDiscovery& discovery, const iox::capro::ServiceDescription& description);

// True once nobody offers `description` (at once when nobody does), false after `wait`.
bool waitForServiceFree(const iox::capro::ServiceDescription& description, std::chrono::milliseconds wait);

}  // namespace robodiff::server
