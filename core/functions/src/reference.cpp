#include "robodiff/functions/reference.hpp"

#include <random>

#include "robodiff/functions/model_function.hpp"
#include "user_evaluator.hpp"

namespace robodiff {

std::vector<Eigen::VectorXd> completeInputs(const FunctionSpec& spec, const std::vector<Eigen::VectorXd>& variable) {
  std::vector<Eigen::VectorXd> all;
  std::size_t next = 0;
  for (const std::string& name : spec.inputNames()) {
    const InputSpec& in = spec.input(name);
    if (in.fixed) {
      all.push_back(Eigen::Map<const Eigen::VectorXd>(in.fixed->data(), static_cast<Eigen::Index>(in.fixed->size())));
    } else {
      if (next >= variable.size())
        throw std::invalid_argument("completeInputs: no value for the variable input '" + name + "'");
      all.push_back(variable[next++]);
    }
  }
  return all;
}

namespace {

// A user function's variable inputs: configurations within limits, vectors in [-1, 1].
std::vector<Eigen::VectorXd> randomUserInputs(const Model& model, const FunctionSpec& spec, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::VectorXd> out;
  const std::map<std::string, int> sizes = detail::inputSizes(model, *spec.user);
  for (const UserInput& in : spec.user->inputs) {
    if (in.kind == UserInput::Kind::Configuration) out.push_back(randomConfiguration(model, rng));
    if (in.kind == UserInput::Kind::Vector) out.push_back(Eigen::VectorXd::NullaryExpr(sizes.at(in.name), [&] { return u(rng); }));
  }
  return out;
}

}  // namespace

std::vector<Eigen::VectorXd> randomRuntimeInputs(const Model& model, const FunctionSpec& spec, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::VectorXd> out;
  if (spec.user) return randomUserInputs(model, spec, rng);
  for (const std::string& name : functionInfo(spec.function).inputs) {
    if (spec.input(name).fixed) continue;
    if (name == "q") {
      out.push_back(randomConfiguration(model, rng));
    } else {
      const double scale = name == "tau" ? 5.0 : 1.0;
      out.push_back(Eigen::VectorXd::NullaryExpr(model.nv, [&] { return scale * u(rng); }));
    }
  }
  for (const OutputSpec& o : spec.outputs)
    if (o.kind == OutputKind::Hessian && !o.fixed_weights) {
      const auto [rows, cols] = valueShape(model, spec.function);
      out.push_back(Eigen::VectorXd::NullaryExpr(rows * cols, [&] { return u(rng); }));
      break;
    }
  return out;
}

Eigen::VectorXd referenceValue(const Model& model, const FunctionSpec& spec, const std::vector<Eigen::VectorXd>& all) {
  Data<double> data(model);
  const Eigen::MatrixXd m = modelFunctionValue(model, data, spec, resolveFrame(model, spec), all);
  Eigen::VectorXd flat(m.size());
  for (Eigen::Index r = 0, k = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) flat[k++] = m(r, c);
  return flat;
}

namespace {

// The inputs moved by a tangent step `step` over the stacked blocks `wrt`.
std::vector<Eigen::VectorXd> moved(const Model& model, const FunctionSpec& spec, std::vector<Eigen::VectorXd> all,
                                   const std::vector<std::string>& wrt, const Eigen::VectorXd& step) {
  const std::vector<std::string>& names = functionInfo(spec.function).inputs;
  Eigen::Index offset = 0;
  for (const std::string& w : wrt) {
    const std::size_t k = static_cast<std::size_t>(std::find(names.begin(), names.end(), w) - names.begin());
    const Eigen::VectorXd d = step.segment(offset, model.nv);
    all.at(k) = w == "q" ? integrate(model, all[k], d) : Eigen::VectorXd(all[k] + d);
    offset += model.nv;
  }
  return all;
}

}  // namespace

Eigen::MatrixXd finiteDifferenceJacobian(const Model& model, const FunctionSpec& spec,
                                         const std::vector<Eigen::VectorXd>& all, const std::vector<std::string>& wrt,
                                         double h) {
  const Eigen::Index n = static_cast<Eigen::Index>(wrt.size()) * model.nv;
  Eigen::MatrixXd J(referenceValue(model, spec, all).size(), n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const Eigen::VectorXd e = Eigen::VectorXd::Unit(n, j) * h;
    J.col(j) = (referenceValue(model, spec, moved(model, spec, all, wrt, e)) -
                referenceValue(model, spec, moved(model, spec, all, wrt, -e))) /
               (2 * h);
  }
  return J;
}

Eigen::MatrixXd finiteDifferenceHessian(const Model& model, const FunctionSpec& spec,
                                        const std::vector<Eigen::VectorXd>& all, const Eigen::VectorXd& weights,
                                        const std::vector<std::string>& wrt, double h) {
  const Eigen::Index n = static_cast<Eigen::Index>(wrt.size()) * model.nv;
  auto f = [&](const Eigen::VectorXd& step) {
    return weights.dot(referenceValue(model, spec, moved(model, spec, all, wrt, step)));
  };
  Eigen::MatrixXd H(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j <= i; ++j) {
      const Eigen::VectorXd ei = Eigen::VectorXd::Unit(n, i) * h, ej = Eigen::VectorXd::Unit(n, j) * h;
      H(i, j) = H(j, i) = (f(ei + ej) - f(ei - ej) - f(ej - ei) + f(-ei - ej)) / (4 * h * h);
    }
  return H;
}

}  // namespace robodiff
