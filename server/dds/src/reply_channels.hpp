#pragma once
// Replies confined to their caller (deploy/security.md, "What is protected"): robodiffd
// answers a request on a reply writer in the caller partition of the request's publication
// (robodiff.caller.<name> or robodiff.operator.<name>, dds_partitions.hpp), the partition a
// client reads replies in. Under DDS Security each identity's permissions let it read the
// reply topic in its own partition only, so no authenticated participant reads another
// caller's replies. Cyclone 0.10 fixes a writer's partitions when it is created, so there
// is one writer per caller partition, a "channel":
//  - made when the request reader matches a publication in a new caller partition
//    (refresh(), on the receive thread), so the client's reply reader has matched it by
//    the time the client sends; or at a request whose partition has none yet;
//  - deleted once no matched request publication uses its partition (refresh());
//  - at most max_channels at once (the bound on the publications robodiffd keeps track of):
//    past it a new caller's requests are not answered, and said so in the log.
// A request from a publication in no caller partition (none, several, or another name)
// has no channel: there is nowhere to answer it, so it is not served.
// A request keeps its channel (shared_ptr) until its reply is written, so deleting a
// channel never loses a reply in flight. Safe from any thread.

#include <dds/dds.h>

#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace robodiff::server::dds_detail {

struct ReplyChannel {
  ReplyChannel(dds_entity_t w, std::string p) : writer(w), partition(std::move(p)) {}
  ~ReplyChannel() { dds_delete(writer); }
  ReplyChannel(const ReplyChannel&) = delete;
  ReplyChannel& operator=(const ReplyChannel&) = delete;
  const dds_entity_t writer;
  const std::string partition;
};
using ReplyChannelPtr = std::shared_ptr<const ReplyChannel>;

class ReplyChannels {
 public:
  // A reply writer in `partition`, or a negative DDS return code.
  using CreateWriter = std::function<dds_entity_t(const std::string& partition)>;
  ReplyChannels(dds_entity_t request_reader, CreateWriter create, std::size_t max_channels)
      : reader_(request_reader), create_(std::move(create)), max_channels_(max_channels) {}
  ~ReplyChannels() { close(); }

  struct Found {
    ReplyChannelPtr channel;  // null: the request cannot be answered
    std::string problem;      // why not (for the log)
  };
  // The channel answering requests of `publication` (a sample info's publication_handle).
  Found forPublication(dds_instance_handle_t publication);
  struct Refreshed {
    // The channels dropped, for the caller to release elsewhere: deleting a writer waits
    // for its replies to be acknowledged (up to Cyclone's WriterLingerDuration, 1 s), which
    // must not hold up the receive thread.
    std::vector<ReplyChannelPtr> dropped;
    // Why a caller partition got no channel (each partition once, until it gets one).
    std::vector<std::string> problems;
  };
  // Re-reads the request reader's matched publications: a channel for every caller
  // partition among them, none for the partitions no longer used.
  Refreshed refresh();
  // Drops every channel (stop); forPublication() then finds none.
  void close();
  std::size_t size() const;

 private:
  // The caller partition of `publication`, or "" with `problem` set.
  std::string callerPartitionOf(dds_instance_handle_t publication, std::string& problem) const;
  // The channel of `partition` in by_partition_, made when missing (mutex_ held).
  Found channelLocked(const std::string& partition);

  const dds_entity_t reader_;
  const CreateWriter create_;
  const std::size_t max_channels_;
  mutable std::mutex mutex_;
  bool closed_ = false;
  std::unordered_map<std::string, ReplyChannelPtr> by_partition_;
  std::unordered_map<dds_instance_handle_t, ReplyChannelPtr> by_publication_;
  std::unordered_set<std::string> refused_;  // partitions whose problem was reported
};

}  // namespace robodiff::server::dds_detail
