#pragma once
// A robot parsed in this process for the double-precision reference (robodiff.reference)
// and the check (robodiff.check): one per robodiff.Model, parsed once from the URDF the
// Model was loaded from, and the same robot as the client's (its canonical hash).
#include <memory>
#include <string>

#include "robodiff/model/model.hpp"

namespace robodiff::python {

class ReferenceModel {
 public:
  // Parses `urdf_text` (a free-flyer root when floating_base). Throws robodiff.Error
  // (INVALID_ARGUMENT) for a URDF that does not load, and when `expected_id` is not
  // empty and the parsed robot's canonical hash differs from it (the file changed since
  // the Model was loaded).
  ReferenceModel(const std::string& urdf_text, bool floating_base, const std::string& expected_id);

  const Model& model() const { return *model_; }
  const std::string& id() const { return id_; }

 private:
  std::shared_ptr<const Model> model_;
  std::string id_;
};

}  // namespace robodiff::python
