#pragma once
// Noticing that the RouDi robodiffd registered with has been replaced. iceoryx 2.0's
// runtime does not survive its RouDi: a restarted RouDi makes new shared-memory segments,
// knows nothing of this process, and the old ports lead nowhere. RouDi is identified by
// its management segment (/dev/shm/iceoryx_mgmt), which each RouDi creates anew: a
// different file there means another RouDi. A missing one means none runs (/readyz
// already says so); robodiffd keeps its DDS side and waits for one to come back.
#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <thread>

namespace robodiff::server {

// The identity of a management segment file: device and inode. Not its times: RouDi's
// writes through its mapping change them while it runs. tmpfs numbers new files afresh.
struct SegmentIdentity {
  dev_t device = 0;
  ino_t inode = 0;
  bool exists = false;
  bool operator==(const SegmentIdentity&) const = default;
};

SegmentIdentity managementSegment(const std::string& path = "/dev/shm/iceoryx_mgmt");

class RoudiWatch {
 public:
  // Remembers the segment present now; `on_replaced(reason)` runs once, on the watch's
  // thread, when another one is seen (checked every `period`).
  RoudiWatch(std::function<void(const std::string& reason)> on_replaced,
             std::chrono::milliseconds period = std::chrono::milliseconds(250),
             std::string segment_path = "/dev/shm/iceoryx_mgmt");
  ~RoudiWatch();
  RoudiWatch(const RoudiWatch&) = delete;
  RoudiWatch& operator=(const RoudiWatch&) = delete;

  bool replaced() const { return replaced_.load(); }

 private:
  void run();

  std::function<void(const std::string&)> on_replaced_;
  std::chrono::milliseconds period_;
  std::string segment_path_;
  SegmentIdentity registered_;
  std::atomic<bool> replaced_{false}, stopping_{false};
  std::thread thread_;
};

}  // namespace robodiff::server
