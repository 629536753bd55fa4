#pragma once
// The caller of a DDS request, from the partition of the publication that wrote it
// (dds_partitions.hpp). Under DDS Security the access-control plugin has checked that
// partition against the writer's signed permissions when it matched the writer, so the
// name is proven ("dds:alice", an operator for robodiff.operator.<name>); on open DDS it is
// only claimed ("user:alice", never an operator). Looked up once per publication (Cyclone's
// dds_get_matched_publication_data), then cached. Safe from any thread.

#include <dds/dds.h>

#include <cstddef>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "robodiff/server/service_api.hpp"

namespace robodiff::server::dds_detail {

// The most request publications (clients) robodiffd keeps track of: callers cached, and
// reply writers (one per caller partition: reply_channels.hpp).
inline constexpr std::size_t kMaxKnownPublications = 4096;

// The partitions of `publication` as the reader matched it; nullopt when it is not (or no
// longer) matched.
std::optional<std::vector<std::string>> publicationPartitions(dds_entity_t reader, dds_instance_handle_t publication);

// The Caller a request partition names: secure ("dds:<name>", operator when the partition
// says so) or open ("user:<name>"); an unknown caller, owner of nothing, for any other.
Caller callerOfRequestPartition(std::string_view partition, bool secure);

class DdsCallers {
 public:
  DdsCallers(dds_entity_t request_reader, bool secure) : reader_(request_reader), secure_(secure) {}
  // The caller behind `publication` (a sample info's publication_handle). A publication
  // that is no longer matched (its writer went away) gives an unknown caller, owner of nothing.
  Caller of(dds_instance_handle_t publication);

 private:
  Caller lookUp(dds_instance_handle_t publication) const;

  const dds_entity_t reader_;
  const bool secure_;
  std::mutex mutex_;
  std::unordered_map<dds_instance_handle_t, Caller> known_;
};

}  // namespace robodiff::server::dds_detail
