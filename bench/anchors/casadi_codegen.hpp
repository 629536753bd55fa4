// bench/anchors: the CasADi side's C source generation, behind an interface that crosses
// libstdc++'s two std::string ABIs. The casadi wheel's libcasadi is built with the old
// one (_GLIBCXX_USE_CXX11_ABI=0), the pin wheel's libraries with the new one, so
// casadi_codegen.cpp alone is compiled with the old ABI, and nothing that holds a
// std::string (pinocchio::Model, RowResult, std::string itself) passes through here:
// the model's tree goes as joints, placements and inertias, names as C strings.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/StdVector>
#include <pinocchio/multibody/joint/joint-generic.hpp>
#include <pinocchio/spatial/inertia.hpp>
#include <pinocchio/spatial/motion.hpp>
#include <pinocchio/spatial/se3.hpp>

namespace anchors::casadi_codegen {

template <class T> using AlignedVector = std::vector<T, Eigen::aligned_allocator<T>>;

// A pinocchio::Model's kinematic tree and inertias, without its names (index 0: the universe).
struct Tree {
  AlignedVector<pinocchio::JointModel> joints;
  std::vector<std::size_t> parents;
  AlignedVector<pinocchio::SE3> placements;  // of each joint in its parent
  AlignedVector<pinocchio::Inertia> inertias;
  Eigen::VectorXd armature;
  pinocchio::Motion gravity;
  // The cost's frame (step_cost): its parent joint and its placement there.
  std::size_t frame_parent = 0;
  pinocchio::SE3 frame_placement = pinocchio::SE3::Identity();
};

// rnea, aba; the step rows (step_rows.hpp): the semi-implicit Euler step, and the step
// with the frame-placement cost l at q.
enum class Algorithm { rnea, aba, euler_step, step_cost };

// The step rows' constants (step_rows.hpp's, passed as numbers: no std::string crosses).
struct StepParameters {
  double dt = 0;
  double control_weight = 0;
  double target[3] = {0, 0, 0};
};

// Writes the C source `c_file` (in the current directory) of the CasADi function `name`,
// Pinocchio's algorithm evaluated on casadi::SX:
//   value:            (q, v, u) -> (y),     y = rnea(q, v, u = a) or aba(q, v, u = tau)
//   with_jacobian:    (q, dq, v, u) -> (y, J), y at q' = integrate(q, dq), J = dy/d[dq, v, u]
//                     dense rows(y) x 3nv, column-major (the tangent-space Jacobian at dq = 0).
//   euler_step:       y = [q_next; v_next] (u = tau); step_cost: y = [q_next; v_next; l].
// Returns false with the reason in `error` (a C string of at most error_size bytes).
bool generateSource(const Tree& tree, Algorithm algorithm, const StepParameters& step, bool with_jacobian,
                    const char* name, const char* c_file, char* error, std::size_t error_size);

// The version of the casadi library linked, e.g. "3.7.2", into `out`.
void casadiVersion(char* out, std::size_t out_size);

}  // namespace anchors::casadi_codegen
