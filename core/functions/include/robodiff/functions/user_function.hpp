// A user function: the user's own function of a robot, written in the expression
// language (docs/function-language.md) over inputs, named definitions and the model's
// primitives, with the outputs wanted (values, Jacobians, gradients, Hessians,
// vector-Jacobian products). Parsed from the JSON spec's "inputs" / "define" /
// "outputs" form; the builder (user_function_builder.hpp) traces and differentiates it.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/language/expression.hpp"

namespace robodiff {

struct UserInput {
  enum class Kind {
    Configuration,  // nq values; derivatives in the tangent space (nv columns)
    Vector,         // `size` values (a number or an expression of nq and nv)
    Fixed,          // constant numbers, folded into the generated code
  };
  std::string name;
  Kind kind = Kind::Vector;
  std::string size;           // Vector: "nv", "3", "2 * nv"
  language::ExprPtr size_expr;
  std::vector<double> fixed;  // Fixed
};

enum class UserOutputKind { Value, Jacobian, Gradient, Hessian, Vjp };
const char* toString(UserOutputKind kind);

struct UserOutput {
  std::string name;  // the output block's name
  UserOutputKind kind = UserOutputKind::Value;
  std::string of;    // an expression: usually a define's or an input's name
  language::ExprPtr of_expr;
  std::vector<std::string> wrt;  // variable inputs, in the order of the columns
  bool sparse = false;           // jacobian, hessian ("layout": "sparse")
  // hessian of a vector: sum_i w_i d2 f_i / dx2 with w an input's name or fixed numbers.
  std::string weights_input;
  std::optional<std::vector<double>> fixed_weights;
  std::string lambda;  // vjp: the input holding lambda (lambda^T d f / d wrt)
};

// A sphere (centre a) or a capsule (segment a-b swept by radius), in the coordinates of
// a frame of the model, or of the world (frame "world").
struct UserShape {
  enum class Kind { Sphere, Capsule };
  Kind kind = Kind::Sphere;
  std::string frame;
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

struct UserDefine {
  std::string name;
  std::string text;
  language::ExprPtr expr;
};

struct UserFunction {
  std::string name = "user_function";  // the C name of the generated function
  std::string source;                  // where the spec came from (a file), for messages
  std::vector<UserInput> inputs;       // in the order written: the runtime blocks' order
  std::vector<UserDefine> defines;
  std::vector<UserOutput> outputs;
  std::map<std::string, UserShape> shapes;
  std::map<std::string, std::size_t> define_index;  // name -> position in `defines`

  const UserInput* input(const std::string& name) const;
  const UserDefine* define(const std::string& name) const;
};

// Limits on what one spec may ask for; past them the spec is refused with SpecTooLarge
// (RESOURCE_EXHAUSTED at the service).
struct UserFunctionLimits {
  std::size_t max_expression_length = 65536;
  int max_depth = 64;                   // nesting of one expression
  std::size_t max_nodes = 100000;       // syntax nodes over the whole spec
  std::size_t max_defines = 1000;
  std::size_t max_inputs = 64;
  std::size_t max_outputs = 64;
  std::size_t max_input_size = 100000;  // entries of one input
};

}  // namespace robodiff
