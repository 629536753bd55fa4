#pragma once
// A robot host's fleet settings (robodiffd's [fleet] section with role = "robot";
// docs/fleet.md): which build hosts to ask, which signatures to trust, what CPU to ask for.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "robodiff/schema/dds_security.hpp"
#include "robodiff/schema/dds_topics.hpp"

namespace robodiff::server {

struct FleetFetchOptions {
  // The build hosts' DDS service names (their dds.service), in order of preference: the
  // first that has a library serves it; when none has it, the first that answers builds it.
  std::vector<std::string> build_hosts;
  std::uint32_t domain_id = dds_codec::kDefaultDomain;
  // This robot's DDS Security identity as a caller of the build hosts; none: open DDS.
  dds_codec::DdsSecurity security;
  // Public keys (files, or directories of *.pub) whose signatures this robot accepts.
  std::vector<std::filesystem::path> trusted_keys;
  // The x86-64 level builds are asked for: "auto" (the highest this CPU supports) or
  // x86-64-v2 / -v3 / -v4 (refused at start when this CPU lacks it).
  std::string target = "auto";
  bool include_sources = false;               // fetch the generated C too
  std::uint32_t chunk_bytes = 256 * 1024;     // asked per FetchArtifactChunk (the build host caps it)
  // A query or chunk not answered within this is a build host lost (the next one is tried).
  std::chrono::milliseconds call_timeout = std::chrono::seconds(5);
  std::chrono::milliseconds match_timeout = std::chrono::seconds(2);  // discovering a build host
  std::chrono::milliseconds build_poll = std::chrono::milliseconds(200);  // asking again while BUILDING
  std::chrono::milliseconds build_wait = std::chrono::minutes(20);        // one build host's build, at most
  std::uint64_t max_artifact_bytes = std::uint64_t{256} << 20;            // a payload larger is refused
};

}  // namespace robodiff::server
