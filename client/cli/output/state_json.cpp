#include "output/state_json.hpp"

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/language/json_problem.hpp"

namespace robodiff::cli {
namespace {

Eigen::VectorXd toVector(const nlohmann::json& value, const std::string& path, const std::string& key) {
  if (!value.is_array()) throw std::invalid_argument(path + ": \"" + key + "\" must be an array of numbers");
  Eigen::VectorXd out(value.size());
  for (size_t i = 0; i < value.size(); ++i) {
    if (!value[i].is_number())
      throw std::invalid_argument(path + ": \"" + key + "\"[" + std::to_string(i) + "] is " + value[i].dump() +
                                  ", not a number");
    out[i] = value[i].get<double>();
    if (!std::isfinite(out[i]))
      throw std::invalid_argument(path + ": \"" + key + "\"[" + std::to_string(i) + "] is not finite");
  }
  return out;
}

// The state file as a JSON object; errors name the file.
nlohmann::json readStateObject(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot open state file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(path + ": not valid JSON: " + language::jsonProblem(e.what()));
  }
  if (!j.is_object()) throw std::invalid_argument(path + ": expected an object {\"q\": [...], \"v\": [...], ...}");
  return j;
}

// "q (7 numbers), v (7 numbers), ..." for messages.
std::string expectedInputs(const std::vector<NamedInput>& wanted) {
  std::string text;
  for (const NamedInput& in : wanted)
    text += (text.empty() ? "" : ", ") + in.name + " (" + std::to_string(in.size) + " numbers" +
            (in.configuration ? ", a configuration" : "") + ")";
  return text;
}

}  // namespace

State readStateFile(const std::string& path) {
  const nlohmann::json j = readStateObject(path);
  State s;
  if (j.contains("q")) s.q = toVector(j["q"], path, "q");
  if (j.contains("v")) s.v = toVector(j["v"], path, "v");
  if (j.contains("a")) s.a = toVector(j["a"], path, "a");
  if (j.contains("tau")) s.tau = toVector(j["tau"], path, "tau");
  if (j.contains("weights")) s.weights = toVector(j["weights"], path, "weights");
  return s;
}

State randomState(const Model& model, std::uint64_t seed, int weight_count) {
  std::mt19937_64 rng(seed);
  State s;
  s.q = randomConfiguration(model, rng);
  auto uniform = [&rng](int n) {
    Eigen::VectorXd x(n);
    for (int i = 0; i < n; ++i) x[i] = -1.0 + 2.0 * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
    return x;
  };
  s.v = uniform(model.nv);
  s.a = uniform(model.nv);
  s.tau = uniform(model.nv);
  if (weight_count > 0) s.weights = uniform(weight_count);
  return s;
}

nlohmann::json drawnStateJson(std::uint64_t seed, const State& state) {
  nlohmann::json j = {{"seed", seed}};
  auto put = [&](const char* key, const std::optional<Eigen::VectorXd>& v) {
    if (v) j[key] = std::vector<double>(v->data(), v->data() + v->size());
  };
  put("q", state.q);
  put("v", state.v);
  put("a", state.a);
  put("tau", state.tau);
  put("weights", state.weights);
  return j;
}

nlohmann::json drawnInputsJson(std::uint64_t seed, const std::vector<NamedInput>& inputs,
                               const std::vector<Eigen::VectorXd>& values) {
  nlohmann::json j = {{"seed", seed}};
  for (std::size_t i = 0; i < inputs.size() && i < values.size(); ++i)
    j[inputs[i].name] = std::vector<double>(values[i].data(), values[i].data() + values[i].size());
  return j;
}

const Eigen::VectorXd& require(const State& state, const Model& model, const std::string& key,
                               const std::string& what, const std::string& source) {
  const std::optional<Eigen::VectorXd>& value =
      key == "q" ? state.q : key == "v" ? state.v : key == "a" ? state.a : state.tau;
  if (!value) throw std::invalid_argument(source + ": no \"" + key + "\", needed by " + what);
  const int expected = key == "q" ? model.nq : model.nv;
  if (value->size() != expected) {
    std::ostringstream s;
    s << source << ": \"" << key << "\" has " << value->size() << " numbers, the model has "
      << (key == "q" ? "nq" : "nv") << " = " << expected;
    throw std::invalid_argument(s.str());
  }
  if (key == "q") checkUnitQuaternions(*value, model, key, source);
  return *value;
}

void checkUnitQuaternions(const Eigen::VectorXd& q, const Model& model, const std::string& key,
                          const std::string& source) {
  for (const Joint& j : model.joints) {
    if (j.type != JointType::FreeFlyer) continue;
    const double norm = q.segment<4>(j.idx_q + 3).norm();
    if (std::abs(norm - 1.0) > 1e-6) {
      std::ostringstream s;
      s << source << ": \"" << key << "\"[" << j.idx_q + 3 << ".." << j.idx_q + 6 << "] (quaternion x y z w of '"
        << j.name << "') has norm " << norm << ", expected a unit quaternion";
      throw std::invalid_argument(s.str());
    }
  }
}

std::vector<Eigen::VectorXd> readNamedInputs(const std::string& path, const Model& model,
                                             const std::vector<NamedInput>& wanted) {
  const nlohmann::json j = readStateObject(path);
  std::vector<Eigen::VectorXd> out;
  for (const NamedInput& in : wanted) {
    if (!j.contains(in.name))
      throw std::invalid_argument(path + ": no \"" + in.name + "\"; the function's inputs are " +
                                  expectedInputs(wanted));
    Eigen::VectorXd value = toVector(j[in.name], path, in.name);
    if (value.size() != in.size)
      throw std::invalid_argument(path + ": \"" + in.name + "\" has " + std::to_string(value.size()) + " numbers, " +
                                  std::to_string(in.size) + " expected; the function's inputs are " +
                                  expectedInputs(wanted));
    if (in.configuration) checkUnitQuaternions(value, model, in.name, path);
    out.push_back(std::move(value));
  }
  return out;
}

const Eigen::VectorXd& requireWeights(const State& state, int count, const std::string& what,
                                      const std::string& source) {
  if (!state.weights)
    throw std::invalid_argument(source + ": no \"weights\", needed by " + what + " (one per entry of the value, " +
                                std::to_string(count) + " numbers)");
  if (state.weights->size() != count)
    throw std::invalid_argument(source + ": \"weights\" has " + std::to_string(state.weights->size()) +
                                " numbers, " + what + " takes " + std::to_string(count) +
                                " (one per entry of the value)");
  return *state.weights;
}

}  // namespace robodiff::cli
