// The robot state a CLI command evaluates at: {"q": [...], "v": [...], "a": [...],
// "tau": [...]} (the golden files' sample shape; keys not needed are ignored), and the
// weights of a weighted Hessian, "weights": [...] (one per entry of the value).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "robodiff/model/model.hpp"

namespace robodiff::cli {

struct State {
  std::optional<Eigen::VectorXd> q, v, a, tau, weights;
};

// Reads a state file; errors name the file, the key and the problem.
State readStateFile(const std::string& path);

// A random state: q within limits (unit quaternion for a free-flyer), v, a, tau uniform
// in [-1, 1], and `weight_count` weights in [-1, 1] if not 0 (drawn last: q, v, a, tau
// are the same for every weight_count).
State randomState(const Model& model, std::uint64_t seed, int weight_count = 0);
// {"seed": N, "q": [...], ...}: what --random-state drew, printed so the state can be
// reused with --state (the drawn arrays) or the seed.
nlohmann::json drawnStateJson(std::uint64_t seed, const State& state);

// The vector `key` of the state, checked against the model (length, unit quaternion).
// `what` names the function that needs it, for the message.
const Eigen::VectorXd& require(const State& state, const Model& model, const std::string& key,
                               const std::string& what, const std::string& source);

// The weights of the state, checked to have `count` entries (the size of the value).
const Eigen::VectorXd& requireWeights(const State& state, int count, const std::string& what,
                                      const std::string& source);

// Throws when a free-flyer's quaternion in configuration `q` (named `key`) is not unit.
void checkUnitQuaternions(const Eigen::VectorXd& q, const Model& model, const std::string& key,
                          const std::string& source);

// An input a user function reads by name ({"q": [...], "u": [...], ...}): its size and
// whether it is a configuration (its free-flyer quaternions must be unit).
struct NamedInput {
  std::string name;
  int size = 0;
  bool configuration = false;
};

// {"seed": N, name: [...], ...}: a user function's inputs drawn by --random-state.
nlohmann::json drawnInputsJson(std::uint64_t seed, const std::vector<NamedInput>& inputs,
                               const std::vector<Eigen::VectorXd>& values);

// The inputs `wanted`, in order, from the state file at `path`; a missing or wrongly
// sized input is an error naming it and listing every expected input with its size.
// Keys not wanted are ignored.
std::vector<Eigen::VectorXd> readNamedInputs(const std::string& path, const Model& model,
                                             const std::vector<NamedInput>& wanted);

}  // namespace robodiff::cli
