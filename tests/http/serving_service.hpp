// A real Service for the HTTP tests: interpreter only (no compiler, no build workers
// busy), no jobs, its cache and log in a temporary directory, marked serving. `adjust`
// may change those options first (a test that needs builds turns compiling on).
#pragma once

#include <cstdio>
#include <functional>
#include <memory>

#include "robodiff/server/service.hpp"
#include "support/temp_dir.hpp"
#include "support/test_paths.hpp"

namespace robodiff::testing {

class ServingService {
 public:
  explicit ServingService(const std::function<void(server::ServiceOptions&)>& adjust = {})
      : log_file_(std::fopen((tmp_ / "service.log").c_str(), "w")), log_(log_file_ ? log_file_ : stderr) {
    server::ServiceOptions o;
    o.cache_dir = tmp_ / "cache";
    o.worker_executable = workerPath().string();
    o.compile = false;
    o.job_workers = 0;
    if (adjust) adjust(o);
    service_ = std::make_unique<server::Service>(o, log_);
    service_->markServing();
  }
  ~ServingService() {
    service_.reset();
    if (log_file_) std::fclose(log_file_);
  }
  ServingService(const ServingService&) = delete;
  ServingService& operator=(const ServingService&) = delete;

  server::Service& operator*() { return *service_; }
  server::Service* operator->() { return service_.get(); }

 private:
  TempDir tmp_;
  std::FILE* log_file_;
  server::Logger log_;
  std::unique_ptr<server::Service> service_;
};

}  // namespace robodiff::testing
