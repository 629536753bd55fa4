#pragma once
// Physically consistent identification: batch/optimization's fitPhysicalParameters (every
// body in log-Cholesky coordinates, Ipopt, regularised towards the URDF's values) on an
// IdentificationProblem, reported like least squares (resultFor, method "physical") plus
// the solver's run (IdentificationResult::solver).
//
// Data: the normal equations W^T D W, W^T D tau of the fitted samples' standard regressor,
// accumulated block by block from problem.fit (the whole W is never copied). Prior: the
// URDF's parameters (problem.prior).
//
// Weighting D, by IdentificationOptions::weighted:
//   false (default)  every row 1, as ordinary least squares;
//   true             each joint's noise sigma_j estimated as for WLS, from the residuals of
//                    an ordinary least-squares pass on the base regressor, and the rows of
//                    joint j weighted 1 / sigma_j^2 (jointWeights, squared). When the samples
//                    excite the base parameters too little for that pass, the rows stay at
//                    1 and the result warns: the physical fit itself needs no excitation
//                    (the prior holds what the data cannot tell).
//
// Every body of the result is physically valid (positive mass, positive definite inertia
// about the centre of mass, strict triangle inequalities), however poor the data, and so
// the result can always be written as a URDF. Also when Ipopt stops short of convergence or
// is cancelled (every iterate is valid): the result then warns with Ipopt's status.

#include "robodiff/batch/identification.hpp"
#include "robodiff/batch/physical_fit.hpp"

namespace robodiff::batch {

// Throws IdentificationError when the fit cannot be set up (sizes, non-finite data or
// prior, a negative regularisation, an Ipopt option it rejects).
IdentificationResult identifyPhysical(const IdentificationProblem& problem, const IdentificationOptions& options = {},
                                      const PhysicalFitOptions& fit = {});

// The normal equations of `stack` with the rows of joint j weighted by joint_weights[j]
// (D's diagonal; empty: all 1), accumulated a block of samples at a time.
NormalEquations stackNormalEquations(const RegressorStack& stack, const Eigen::VectorXd& joint_weights = {});

}  // namespace robodiff::batch
