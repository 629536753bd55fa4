#pragma once
// robodiffd's [fleet] section into the service's options (docs/fleet.md): a build host
// signs and serves artifacts; a robot host gets an ArtifactFetcher over DDS.

#include "robodiff/server/log.hpp"
#include "robodiff/server/service.hpp"
#include "server_config.hpp"

namespace robodiff::server {

// Fills options.artifact_serving (role build) or options.artifact_source (role robot).
// Throws ConfigError naming the key when the section does not fit the role, and the
// fetcher's errors (a key file, the target, DDS) as they are.
void applyFleetSettings(const ServerConfig& config, ServiceOptions& options, Logger& log);

}  // namespace robodiff::server
