// DdsCallers: a request's publication -> its partition -> the caller.
#include "caller_identity.hpp"

#include <string>

#include "robodiff/schema/dds_partitions.hpp"

namespace robodiff::server::dds_detail {

namespace {

// Never a caller a partition can name (no partition-derived name has a '?').
Caller unknownCaller() { return Caller{"dds:?unknown", false, false}; }

}  // namespace

Caller callerOfRequestPartition(std::string_view partition, bool secure) {
  const auto named = dds_codec::callerOfPartition(partition);
  if (!named) return unknownCaller();
  if (secure) return Caller{"dds:" + named->name, named->operator_, true};
  return Caller{"user:" + named->name, false, false};
}

Caller DdsCallers::of(dds_instance_handle_t publication) {
  {
    std::lock_guard lock(mutex_);
    if (const auto it = known_.find(publication); it != known_.end()) return it->second;
  }
  Caller caller = lookUp(publication);
  if (caller.name == unknownCaller().name) return caller;  // not cached: it may be matched a moment later
  std::lock_guard lock(mutex_);
  if (known_.size() >= kMaxKnownPublications) known_.clear();
  known_.emplace(publication, caller);
  return caller;
}

std::optional<std::vector<std::string>> publicationPartitions(dds_entity_t reader, dds_instance_handle_t publication) {
  dds_builtintopic_endpoint_t* endpoint = dds_get_matched_publication_data(reader, publication);
  if (endpoint == nullptr) return std::nullopt;
  std::vector<std::string> partitions;
  uint32_t count = 0;
  char** names = nullptr;
  if (endpoint->qos && dds_qget_partition(endpoint->qos, &count, &names)) {
    for (uint32_t i = 0; i < count; ++i) {
      partitions.emplace_back(names[i]);
      dds_free(names[i]);
    }
    dds_free(names);
  }
  dds_builtintopic_free_endpoint(endpoint);
  return partitions;
}

Caller DdsCallers::lookUp(dds_instance_handle_t publication) const {
  const auto partitions = publicationPartitions(reader_, publication);
  // One partition per client writer; a writer in several is no caller of ours.
  if (!partitions || partitions->size() != 1) return unknownCaller();
  return callerOfRequestPartition(partitions->front(), secure_);
}

}  // namespace robodiff::server::dds_detail
