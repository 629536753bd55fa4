// ReplyChannels: one reply writer per caller partition, made and dropped with the request
// publications the server matches.
#include "reply_channels.hpp"

#include "caller_identity.hpp"
#include "robodiff/schema/dds_partitions.hpp"
#include "robodiff/schema/dds_topics.hpp"

namespace robodiff::server::dds_detail {

std::string ReplyChannels::callerPartitionOf(dds_instance_handle_t publication, std::string& problem) const {
  const auto partitions = publicationPartitions(reader_, publication);
  if (!partitions) {
    problem = "its publication is no longer matched";
    return {};
  }
  if (partitions->size() != 1) {
    problem = "its publication is in " + std::to_string(partitions->size()) + " partitions, not one caller partition";
    return {};
  }
  const std::string& partition = partitions->front();
  if (!dds_codec::callerOfPartition(partition)) {
    problem = "its publication's partition '" + partition.substr(0, 120) + "' names no caller";
    return {};
  }
  return partition;
}

ReplyChannels::Found ReplyChannels::channelLocked(const std::string& partition) {
  if (closed_) return {nullptr, "the DDS server is stopping"};
  if (const auto it = by_partition_.find(partition); it != by_partition_.end()) return {it->second, {}};
  if (by_partition_.size() >= max_channels_)
    return {nullptr, "robodiffd already answers " + std::to_string(max_channels_) +
                         " caller partitions, the most it keeps reply writers for"};
  const dds_entity_t writer = create_(partition);
  if (writer < 0) return {nullptr, dds_codec::ddsError("dds_create_writer", writer) + " in partition " + partition};
  auto channel = std::make_shared<const ReplyChannel>(writer, partition);
  by_partition_.emplace(partition, channel);
  return {channel, {}};
}

ReplyChannels::Found ReplyChannels::forPublication(dds_instance_handle_t publication) {
  {
    std::lock_guard lock(mutex_);
    if (const auto it = by_publication_.find(publication); it != by_publication_.end()) return {it->second, {}};
  }
  std::string problem;
  const std::string partition = callerPartitionOf(publication, problem);
  if (partition.empty()) return {nullptr, problem};
  std::lock_guard lock(mutex_);
  Found found = channelLocked(partition);
  if (found.channel) {
    if (by_publication_.size() >= max_channels_) by_publication_.clear();  // refresh() fills it again
    by_publication_.emplace(publication, found.channel);
  }
  return found;
}

ReplyChannels::Refreshed ReplyChannels::refresh() {
  std::vector<dds_instance_handle_t> handles(64);
  for (;;) {
    const dds_return_t n = dds_get_matched_publications(reader_, handles.data(), handles.size());
    if (n < 0) return {};  // the reader is gone (stopping)
    if (static_cast<std::size_t>(n) <= handles.size()) {
      handles.resize(static_cast<std::size_t>(n));
      break;
    }
    handles.resize(static_cast<std::size_t>(n));
  }
  std::unordered_map<std::string, ReplyChannelPtr> kept;
  std::unordered_map<dds_instance_handle_t, ReplyChannelPtr> publications;
  Refreshed result;
  {
    std::lock_guard lock(mutex_);
    if (closed_) return {};
    for (const dds_instance_handle_t handle : handles) {
      ReplyChannelPtr channel;
      if (const auto it = by_publication_.find(handle); it != by_publication_.end()) {
        channel = it->second;
      } else {
        std::string problem;
        const std::string partition = callerPartitionOf(handle, problem);
        if (partition.empty()) continue;
        if (const auto k = kept.find(partition); k != kept.end()) {
          channel = k->second;
        } else {
          Found found = channelLocked(partition);
          if (!found.channel && refused_.size() < max_channels_ && refused_.insert(partition).second)
            result.problems.push_back(found.problem);
          channel = std::move(found.channel);
        }
      }
      if (!channel) continue;
      refused_.erase(channel->partition);
      kept.emplace(channel->partition, channel);
      publications.emplace(handle, channel);
    }
    for (auto& [partition, channel] : by_partition_)
      if (!kept.count(partition)) result.dropped.push_back(std::move(channel));
    by_partition_ = std::move(kept);
    by_publication_ = std::move(publications);
  }
  return result;
}

void ReplyChannels::close() {
  std::unordered_map<std::string, ReplyChannelPtr> dropped;
  std::unordered_map<dds_instance_handle_t, ReplyChannelPtr> publications;
  std::lock_guard lock(mutex_);
  closed_ = true;
  dropped.swap(by_partition_);
  publications.swap(by_publication_);
}

std::size_t ReplyChannels::size() const {
  std::lock_guard lock(mutex_);
  return by_partition_.size();
}

}  // namespace robodiff::server::dds_detail
