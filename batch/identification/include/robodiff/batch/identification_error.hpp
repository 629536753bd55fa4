#pragma once
// The error of the identification layer: bad sample files, samples that do not excite
// the base parameters, identified values that cannot be written as a URDF. The message
// names the file, the line, the column or the parameter and the value.

#include <stdexcept>

namespace robodiff::batch {

class IdentificationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace robodiff::batch
