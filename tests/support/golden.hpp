// Reference values computed by Pinocchio (../shared/golden, layout in its README), and
// the comparison rule the tests use against them.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "robodiff/spatial/se3.hpp"

namespace robodiff::testing {

struct GoldenFrame {
  std::string name, type, parent_joint;
};

struct GoldenSample {
  Eigen::VectorXd q, v, a, tau, nle, gravity_torque, ddq;
  Eigen::MatrixXd M, dtau_dq, dtau_dv, dddq_dq, dddq_dv, regressor;
  std::map<std::string, SE3<double>> frame_placements;
  std::map<std::string, Eigen::MatrixXd> ee_jacobian_local_world_aligned;
};

struct GoldenRobot {
  std::string robot;
  std::filesystem::path urdf;  // absolute
  bool free_flyer = false;
  int nq = 0, nv = 0;
  Eigen::Vector3d gravity;
  std::vector<std::string> joint_names;
  std::vector<std::string> joint_types;
  std::vector<GoldenFrame> frames;
  std::vector<std::string> ee_frames;
  Eigen::VectorXd inertial_parameters;
  std::vector<GoldenSample> samples;
};

// Loads golden/<name>.json from the shared folder.
GoldenRobot loadGolden(const std::filesystem::path& shared_dir, const std::string& name);

// The golden files present: panda, ur5, talos, talos_ff.
std::vector<std::string> goldenNames();

// Element-wise |actual - expected| <= rel * max(|expected|, floor), with the floor at
// 1e-3 of the largest |expected| (and at least 1e-6): relative where values are large,
// absolute near zero.
::testing::AssertionResult matricesAgree(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected,
                                         double rel = 1e-9);

}  // namespace robodiff::testing
