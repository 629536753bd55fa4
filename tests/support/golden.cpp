#include "support/golden.hpp"

#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

#include "support/test_paths.hpp"

namespace robodiff::testing {
namespace {

Eigen::VectorXd vec(const nlohmann::json& j) {
  Eigen::VectorXd v(j.size());
  for (size_t i = 0; i < j.size(); ++i) v[i] = j[i].get<double>();
  return v;
}

Eigen::MatrixXd mat(const nlohmann::json& j) {
  if (j.empty()) return Eigen::MatrixXd();
  Eigen::MatrixXd m(j.size(), j[0].size());
  for (size_t r = 0; r < j.size(); ++r)
    for (size_t c = 0; c < j[r].size(); ++c) m(r, c) = j[r][c].get<double>();
  return m;
}

}  // namespace

std::vector<std::string> goldenNames() { return {"panda", "ur5", "talos", "talos_ff"}; }

GoldenRobot loadGolden(const std::filesystem::path& shared_dir, const std::string& name) {
  nlohmann::json j = nlohmann::json::parse(readFile(shared_dir / "golden" / (name + ".json")));
  GoldenRobot g;
  g.robot = j["robot"];
  g.urdf = shared_dir / j["urdf"].get<std::string>();
  g.free_flyer = j["root_joint"] == "freeflyer";
  g.nq = j["nq"];
  g.nv = j["nv"];
  g.gravity = vec(j["gravity"]);
  for (const auto& joint : j["joints"]) {
    g.joint_names.push_back(joint["name"]);
    g.joint_types.push_back(joint["type"]);
  }
  for (const auto& f : j["frames"]) g.frames.push_back({f["name"], f["type"], f["parent_joint"]});
  for (const auto& f : j["ee_frames"]) g.ee_frames.push_back(f);
  g.inertial_parameters = vec(j["inertial_parameters"]);
  for (const auto& s : j["samples"]) {
    GoldenSample x;
    x.q = vec(s["q"]);
    x.v = vec(s["v"]);
    x.a = vec(s["a"]);
    x.tau = vec(s["tau"]);
    x.nle = vec(s["nle"]);
    x.gravity_torque = vec(s["gravity_torque"]);
    x.ddq = vec(s["ddq"]);
    x.M = mat(s["M"]);
    x.dtau_dq = mat(s["dtau_dq"]);
    x.dtau_dv = mat(s["dtau_dv"]);
    x.dddq_dq = mat(s["dddq_dq"]);
    x.dddq_dv = mat(s["dddq_dv"]);
    x.regressor = mat(s["regressor"]);
    for (const auto& [frame, placement] : s["frame_placements"].items()) {
      SE3<double> m;
      m.translation = vec(placement["p"]);
      m.rotation = mat(placement["R"]);
      x.frame_placements[frame] = m;
    }
    for (const auto& [frame, jac] : s["ee_jacobian_local_world_aligned"].items())
      x.ee_jacobian_local_world_aligned[frame] = mat(jac);
    g.samples.push_back(std::move(x));
  }
  return g;
}

::testing::AssertionResult matricesAgree(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected,
                                         double rel) {
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols())
    return ::testing::AssertionFailure() << "shape " << actual.rows() << "x" << actual.cols() << ", expected "
                                         << expected.rows() << "x" << expected.cols();
  double floor = std::max(1e-6, 1e-3 * (expected.size() ? expected.cwiseAbs().maxCoeff() : 0.0));
  double worst = 0;
  Eigen::Index wr = 0, wc = 0;
  for (Eigen::Index r = 0; r < expected.rows(); ++r)
    for (Eigen::Index c = 0; c < expected.cols(); ++c) {
      double err = std::abs(actual(r, c) - expected(r, c)) / std::max(std::abs(expected(r, c)), floor);
      if (!(err <= worst)) worst = err, wr = r, wc = c;  // also catches NaN
    }
  if (worst <= rel) return ::testing::AssertionSuccess();
  std::ostringstream s;
  s.precision(17);
  s << "worst relative error " << worst << " > " << rel << " at (" << wr << "," << wc << "): got "
    << actual(wr, wc) << ", expected " << expected(wr, wc);
  return ::testing::AssertionFailure() << s.str();
}

}  // namespace robodiff::testing
