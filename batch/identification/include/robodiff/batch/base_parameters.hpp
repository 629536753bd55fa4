#pragma once
// Base parameters: the combinations of standard inertial parameters that the joint
// torques determine (Gautier's base parameters), found by QR with column pivoting.
//
// With W P = Q [R11 R12; 0 0] (R11 r x r, r the rank), the independent columns W1 = W P1
// and the dependent ones W2 = W1 R11^-1 R12, so
//   W pi = W1 pi_base,   pi_base = pi_ind + K pi_dep,   K = R11^-1 R12,
// i.e. pi_base = B pi with B = [I K] P^T (r x n). Each base parameter is named after its
// leading (independent) standard parameter; independent and dependent indices are kept
// in ascending parameter order.
//
// Which combinations are identifiable depends on the kinematics only, not on the data, so
// computeBaseParameters decides it on a regressor stacked from random states (uniform
// within the joint limits, v and a uniform in [-1, 1]) computed by core/dynamics: the
// standard, data-independent choice, the same for every data set of a robot. Whether the
// data excite all of them is checked by the least-squares fit (its condition number).
//
// Rank tolerance: column j of the pivoted R counts as independent when |R_jj| > tolerance *
// |R_00| (default 1e-8, about sqrt(machine epsilon)); structurally dependent columns sit at
// about 1e-15 and the gap is reported. K entries below 1e-10 in magnitude are rounding
// noise and set to zero.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/batch/parameter_layout.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

struct BaseParameterOptions {
  int samples = 0;            // random states; 0: enough for 4 rows per standard parameter (at least 20)
  std::uint64_t seed = 20240607;
  double tolerance = 1e-8;    // relative rank tolerance on the pivoted R's diagonal
};

struct BaseParameters {
  int standard_count = 0;        // n = 10 njoints
  std::vector<int> independent;  // r standard indices, ascending: base parameter k leads with independent[k]
  std::vector<int> dependent;    // the other n - r, ascending
  Eigen::MatrixXd K;             // r x (n - r): pi_base = pi[independent] + K pi[dependent]
  Eigen::MatrixXd B;             // r x n: pi_base = B pi
  std::vector<int> no_effect;    // standard parameters whose regressor column is zero (in no base parameter)
  double tolerance = 0;
  double smallest_kept = 0, largest_dropped = 0;  // |R_jj| / |R_00| either side of the rank cut

  int size() const { return static_cast<int>(independent.size()); }

  Eigen::VectorXd fromStandard(const Eigen::VectorXd& pi) const { return B * pi; }

  // The independent columns of a stacked regressor: W_base (N nv x r), with W pi = W_base B pi.
  template <class Derived> Eigen::MatrixXd baseColumns(const Eigen::MatrixBase<Derived>& W) const {
    return W(Eigen::all, independent);
  }

  // The standard parameter vector closest to `prior` whose base parameters are `base`, in
  // the norm sum_i ((pi_i - prior_i) / scale_i)^2:
  //   prior + S B^T (B S B^T)^-1 (base - B prior),  S = diag(scale^2).
  // The directions the data cannot see keep the prior's values. With scales of each
  // parameter's size (parameterScales), the change is shared out as relative changes, so a
  // correction that comes from a mass is not dumped onto a small inertia. Empty scales: 1.
  Eigen::VectorXd complete(const Eigen::VectorXd& base, const Eigen::VectorXd& prior,
                           const Eigen::VectorXd& scales = Eigen::VectorXd()) const;

  // When standard parameter i is determined by the base parameters on its own: c with
  // pi_i = c^T pi_base; nullopt when it is not (it appears only in combinations).
  std::optional<Eigen::VectorXd> combinationFor(int i) const;

  // Base parameter k as text, e.g. "Izz_link1 + 0.0081*m_link2 + Iyy_link2".
  std::string describe(int k, const ParameterLayout& layout) const;
  std::string name(int k, const ParameterLayout& layout) const { return layout.names.at(independent.at(k)); }
};

// The base parameters of `model` from random states (above).
BaseParameters computeBaseParameters(const Model& model, const BaseParameterOptions& options = {});

// The base parameters of a given stacked regressor (a data-dependent choice, e.g. to see
// what a particular data set identifies).
BaseParameters baseParametersOf(const Eigen::Ref<const Eigen::MatrixXd>& W, double tolerance = 1e-8);

}  // namespace robodiff::batch
