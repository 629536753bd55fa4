#include "roudi_watch.hpp"

#include <sys/stat.h>

namespace robodiff::server {

SegmentIdentity managementSegment(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {};
  return {st.st_dev, st.st_ino, true};
}

RoudiWatch::RoudiWatch(std::function<void(const std::string&)> on_replaced, std::chrono::milliseconds period,
                       std::string segment_path)
    : on_replaced_(std::move(on_replaced)),
      period_(period),
      segment_path_(std::move(segment_path)),
      registered_(managementSegment(segment_path_)),
      thread_([this] { run(); }) {}

RoudiWatch::~RoudiWatch() {
  stopping_ = true;
  thread_.join();
}

void RoudiWatch::run() {
  while (!stopping_) {
    std::this_thread::sleep_for(period_);
    const SegmentIdentity now = managementSegment(segment_path_);
    // Missing: no RouDi now (or one starting); only a different file is another RouDi.
    if (!now.exists || now == registered_) continue;
    if (!replaced_.exchange(true))
      on_replaced_(registered_.exists ? "RouDi was restarted: " + segment_path_ + " is a new segment"
                                      : "a RouDi appeared after robodiffd registered without one");
    return;
  }
}

}  // namespace robodiff::server
