#include <random>

#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/lie_group.hpp"
#include "robodiff/functions/reference.hpp"
#include "user_evaluator.hpp"

namespace robodiff {

using detail::Value;

namespace {

Value<double> evaluateOutput(const Model& model, const FunctionSpec& spec, std::size_t k, const std::vector<Eigen::VectorXd>& all) {
  const UserFunction& f = *spec.user;
  std::map<std::string, Value<double>> inputs;
  for (std::size_t i = 0; i < f.inputs.size(); ++i) {
    Value<double> v;
    v.m = all.at(i);
    v.configuration = f.inputs[i].kind == UserInput::Kind::Configuration;
    inputs[f.inputs[i].name] = v;
  }
  const detail::PrimitiveContext context{model, f, true, 0, nullptr};
  detail::Evaluator<double> ev(context, inputs);
  return ev.output(k);
}

Eigen::VectorXd flat(const Eigen::MatrixXd& m) {
  Eigen::VectorXd out(m.size());
  for (Eigen::Index r = 0, k = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) out[k++] = m(r, c);
  return out;
}

std::size_t inputIndex(const UserFunction& f, const std::string& name) {
  for (std::size_t i = 0; i < f.inputs.size(); ++i)
    if (f.inputs[i].name == name) return i;
  throw std::invalid_argument("no input named " + name);
}

int tangentSize(const Model& model, const UserFunction& f, const std::vector<Eigen::VectorXd>& all, const std::string& w) {
  const std::size_t i = inputIndex(f, w);
  return f.inputs[i].kind == UserInput::Kind::Configuration ? model.nv : static_cast<int>(all[i].size());
}

// The inputs moved by `step` over the stacked tangents of `wrt`.
std::vector<Eigen::VectorXd> moved(const Model& model, const UserFunction& f, std::vector<Eigen::VectorXd> all,
                                   const std::vector<std::string>& wrt, const Eigen::VectorXd& step) {
  Eigen::Index offset = 0;
  for (const std::string& w : wrt) {
    const std::size_t i = inputIndex(f, w);
    const int n = tangentSize(model, f, all, w);
    const Eigen::VectorXd d = step.segment(offset, n);
    all[i] = f.inputs[i].kind == UserInput::Kind::Configuration ? integrate(model, all[i], d) : Eigen::VectorXd(all[i] + d);
    offset += n;
  }
  return all;
}

int tangentColumns(const Model& model, const UserFunction& f, const std::vector<Eigen::VectorXd>& all,
                   const std::vector<std::string>& wrt) {
  int n = 0;
  for (const std::string& w : wrt) n += tangentSize(model, f, all, w);
  return n;
}

// Central differences of output k's expression (a configuration by its tangent difference).
Eigen::MatrixXd jacobianByDifferences(const Model& model, const FunctionSpec& spec, std::size_t k,
                                      const std::vector<Eigen::VectorXd>& all, const std::vector<std::string>& wrt, double h) {
  const UserFunction& f = *spec.user;
  bool configuration = false;
  const Eigen::VectorXd f0 = userReferenceValue(model, spec, k, all, &configuration);
  auto at = [&](const Eigen::VectorXd& step) {
    const Eigen::VectorXd y = userReferenceValue(model, spec, k, moved(model, f, all, wrt, step));
    return configuration ? differenceConfiguration<double>(model, f0, y) : y;
  };
  const int n = tangentColumns(model, f, all, wrt);
  Eigen::MatrixXd J(configuration ? model.nv : f0.size(), n);
  for (int j = 0; j < n; ++j) {
    const Eigen::VectorXd e = Eigen::VectorXd::Unit(n, j) * h;
    J.col(j) = (at(e) - at(-e)) / (2 * h);
  }
  return J;
}

Eigen::MatrixXd hessianByDifferences(const Model& model, const FunctionSpec& spec, std::size_t k,
                                     const std::vector<Eigen::VectorXd>& all, const Eigen::VectorXd& weights,
                                     const std::vector<std::string>& wrt, double h) {
  const UserFunction& f = *spec.user;
  auto value = [&](const Eigen::VectorXd& step) { return weights.dot(userReferenceValue(model, spec, k, moved(model, f, all, wrt, step))); };
  const int n = tangentColumns(model, f, all, wrt);
  Eigen::MatrixXd H(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j <= i; ++j) {
      const Eigen::VectorXd ei = Eigen::VectorXd::Unit(n, i) * h, ej = Eigen::VectorXd::Unit(n, j) * h;
      H(i, j) = H(j, i) = (value(ei + ej) - value(ei - ej) - value(ej - ei) + value(-ei - ej)) / (4 * h * h);
    }
  return H;
}

}  // namespace

Eigen::VectorXd userReferenceValue(const Model& model, const FunctionSpec& spec, std::size_t output,
                                   const std::vector<Eigen::VectorXd>& all, bool* configuration) {
  const Value<double> v = evaluateOutput(model, spec, output, all);
  if (configuration) *configuration = v.configuration;
  return flat(v.m);
}

std::vector<Eigen::MatrixXd> userReferenceOutputs(const Model& model, const FunctionSpec& spec,
                                                  const std::vector<Eigen::VectorXd>& all, double h_jacobian, double h_hessian) {
  const UserFunction& f = *spec.user;
  std::vector<Eigen::MatrixXd> out;
  for (std::size_t k = 0; k < f.outputs.size(); ++k) {
    const UserOutput& o = f.outputs[k];
    switch (o.kind) {
      case UserOutputKind::Value: out.push_back(evaluateOutput(model, spec, k, all).m); break;
      case UserOutputKind::Jacobian: out.push_back(jacobianByDifferences(model, spec, k, all, o.wrt, h_jacobian)); break;
      case UserOutputKind::Gradient: out.push_back(jacobianByDifferences(model, spec, k, all, o.wrt, h_jacobian).transpose()); break;
      case UserOutputKind::Vjp: {
        const Eigen::VectorXd& lambda = all[inputIndex(f, o.lambda)];
        out.push_back(jacobianByDifferences(model, spec, k, all, o.wrt, h_jacobian).transpose() * lambda);
        break;
      }
      case UserOutputKind::Hessian: {
        const Eigen::VectorXd weights =
            !o.weights_input.empty() ? all[inputIndex(f, o.weights_input)]
            : o.fixed_weights ? Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(o.fixed_weights->data(), o.fixed_weights->size()))
                              : Eigen::VectorXd::Ones(1);
        out.push_back(hessianByDifferences(model, spec, k, all, weights, o.wrt, h_hessian));
        break;
      }
    }
  }
  return out;
}

}  // namespace robodiff
