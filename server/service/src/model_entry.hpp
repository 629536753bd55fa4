#pragma once
// A loaded model: the robot as LoadModel received it (the URDF text is kept: a compiled
// build loads it again in a worker process) and as loaded. Immutable except the counts,
// which the registry guards.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "holders.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::server::detail {

struct ModelEntry {
  std::string id;           // canonical hash (hex)
  std::string urdf;         // the text first loaded under this id
  std::string source_name;  // names the URDF in messages (options_json "source_name")
  bool floating_base = false;
  std::shared_ptr<const Model> model;
  std::vector<std::string> joint_names;  // moving joints, in model order
  std::vector<std::string> frame_names;

  // Guarded by the registry's mutex.
  Holders holders;               // LoadModel calls not yet released, per caller
  std::uint32_t functions = 0;   // loaded functions of this model (they keep it loaded)

  // What a person calls it: the URDF's robot name, with the source name when one was given.
  std::string displayName() const {
    const std::string robot = model ? model->name : std::string();
    if (source_name.empty() || source_name == "<urdf>" || source_name == robot) return robot;
    return robot.empty() ? source_name : robot + " (" + source_name + ")";
  }
};

}  // namespace robodiff::server::detail
