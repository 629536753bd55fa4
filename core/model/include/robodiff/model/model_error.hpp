// The errors of loading a robot model.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace robodiff {

// A URDF that cannot be turned into a model. The message names the source (file or
// "<string>"), the line, the element and the offending value.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The URDF exceeds one of the UrdfLimits (urdf_limits.hpp); the message names the limit
// and the value found. A server answers RESOURCE_EXHAUSTED.
class ModelTooLarge : public ModelError {
 public:
  ModelTooLarge(const std::string& message, std::string limit_name, std::uint64_t value, std::uint64_t limit)
      : ModelError(message), limit_name_(std::move(limit_name)), value_(value), limit_(limit) {}
  const std::string& limitName() const { return limit_name_; }  // e.g. "max_depth"
  std::uint64_t value() const { return value_; }
  std::uint64_t limit() const { return limit_; }

 private:
  std::string limit_name_;
  std::uint64_t value_ = 0, limit_ = 0;
};

// The URDF describes no physical robot: a negative mass, an inertia that is not positive
// semi-definite or violates the triangle inequality, or a moving body that leaves the
// mass matrix singular. The message names the link (or joint).
class PhysicallyInvalidModel : public ModelError {
 public:
  using ModelError::ModelError;
};

}  // namespace robodiff
