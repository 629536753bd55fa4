#include "fleet_setup.hpp"

#include "robodiff/schema/dds_security.hpp"
#include "robodiff/server/artifact_fetcher.hpp"

namespace robodiff::server {
namespace {

void setUpBuildHost(const ServerConfig& config, ServiceOptions& options) {
  const FleetSettings& f = config.fleet;
  if (f.signing_key.empty())
    throw ConfigError("fleet.role = \"build\" needs fleet.signing_key: the private key it signs artifacts with "
                      "(robodiff keygen --out DIR --name NAME writes DIR/NAME.key)");
  if (!config.dds.enabled)
    throw ConfigError("fleet.role = \"build\" serves robots over DDS, but dds.enabled = false");
  ArtifactServingOptions& s = options.artifact_serving;
  s.enabled = true;
  s.signing_key = f.signing_key;
  s.build_for_robots = f.build_for_robots;
  s.max_builds_per_caller = f.max_builds_per_robot;
  s.chunk_bytes = static_cast<std::uint32_t>(std::min<std::uint64_t>(f.chunk_size, config.dds.max_sample_bytes));
  s.chunk_delay = f.chunk_delay;
}

// The robot calls its build hosts with its server identity (dds.security_identity) unless
// fleet.security_identity names another: Cyclone DDS 0.10 holds one permissions document
// per domain in a process, so both participants need the one that grants both
// (`robodiff security add-server NAME --also-calls BUILD_SERVICE`).
dds_codec::DdsSecurity robotSecurity(const ServerConfig& config) {
  if (config.dds.security.empty()) return {};
  const std::string& name =
      config.fleet.security_identity.empty() ? config.dds.security_identity : config.fleet.security_identity;
  try {
    return dds_codec::keystoreIdentity(config.dds.security, name);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(std::string("fleet.security_identity: ") + e.what());
  }
}

void setUpRobot(const ServerConfig& config, ServiceOptions& options, Logger& log) {
  const FleetSettings& f = config.fleet;
  FleetFetchOptions o;
  o.build_hosts = f.build_hosts;
  if (config.dds.domain >= 0) o.domain_id = static_cast<std::uint32_t>(config.dds.domain);
  o.security = robotSecurity(config);
  o.trusted_keys = f.trusted_keys;
  o.target = f.target;
  o.include_sources = f.fetch_sources;
  o.chunk_bytes = static_cast<std::uint32_t>(std::min<std::uint64_t>(f.chunk_size, config.dds.max_sample_bytes));
  o.call_timeout = f.call_timeout;
  o.build_wait = f.build_wait;
  o.max_artifact_bytes = f.max_artifact;
  try {
    options.artifact_source = std::make_shared<ArtifactFetcher>(std::move(o), log);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(e.what());
  }
}

}  // namespace

void applyFleetSettings(const ServerConfig& config, ServiceOptions& options, Logger& log) {
  if (config.fleet.role == "build") setUpBuildHost(config, options);
  if (config.fleet.role == "robot") setUpRobot(config, options, log);
}

}  // namespace robodiff::server
