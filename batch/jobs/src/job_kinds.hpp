#pragma once
// One pair of functions per job kind (one file each): check the parameters, run the job.
#include <nlohmann/json.hpp>

#include "robodiff/batch/batch_job.hpp"

namespace robodiff::batch {

// trajectory_job.cpp: a function evaluated along a trajectory file.
void validateTrajectoryParams(const nlohmann::json& params, const FileAccess& files);
nlohmann::json runTrajectoryKind(const nlohmann::json& params, const BatchJobContext& context);

// trajopt_job.cpp: a trajectory optimised with Ipopt.
void validateTrajoptParams(const nlohmann::json& params, const FileAccess& files);
nlohmann::json runTrajoptKind(const nlohmann::json& params, const BatchJobContext& context);

// identify_job.cpp: inertial parameters from measured samples.
void validateIdentifyParams(const nlohmann::json& params, const FileAccess& files);
nlohmann::json runIdentifyKind(const nlohmann::json& params, const BatchJobContext& context);

}  // namespace robodiff::batch
