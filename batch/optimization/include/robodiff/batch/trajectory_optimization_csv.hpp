#pragma once
// An optimised trajectory as CSV: a header `t,q_<joint>...,v_<joint>...,a_<joint>...,
// tau_<joint>...` and one row per knot, numbers in their shortest round-trip form.
// (batch/trajectory has a general trajectory writer; the two should become one.)

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "robodiff/batch/trajectory_optimization.hpp"

namespace robodiff::batch {

// `joint_names`: one per column of the trajectory (nv).
void writeTrajectoryCsv(std::ostream& out, const Trajectory& trajectory, const std::vector<std::string>& joint_names);

// Written to a temporary file beside `path`, then renamed into place; throws
// AtomicFileError (a std::runtime_error) naming the path when it cannot be written.
void writeTrajectoryCsvFile(const std::filesystem::path& path, const Trajectory& trajectory,
                            const std::vector<std::string>& joint_names);

}  // namespace robodiff::batch
