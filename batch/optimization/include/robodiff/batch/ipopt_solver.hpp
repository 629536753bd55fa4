#pragma once
// Solving a NonlinearProgram with Ipopt (3.11, MUMPS: the linear solver Debian ships),
// exact Hessians by default. Ipopt prints nothing unless print_level says so.

#include <string>
#include <utility>
#include <vector>

#include "robodiff/batch/nonlinear_program.hpp"

namespace robodiff::batch {

struct IpoptOptions {
  int max_iterations = 3000;
  double tolerance = 1e-8;           // Ipopt's tol (scaled NLP error)
  double acceptable_tolerance = 1e-6;
  double max_seconds = 0;            // 0: no limit (Ipopt's max_cpu_time otherwise)
  int print_level = 0;               // 0 silent .. 12; 5 is Ipopt's usual output
  bool exact_hessian = true;         // false: limited-memory quasi-Newton (the Hessian is not asked for)
  std::string derivative_test;       // "", "first-order" or "second-order": Ipopt checks the derivatives
  // Any other Ipopt option, as (name, value) text pairs (numeric values parsed).
  std::vector<std::pair<std::string, std::string>> extra;
};

struct IpoptResult {
  bool success = false;         // solved to tolerance (or acceptable level)
  std::string status;           // Ipopt's return, e.g. "Solve_Succeeded", "Maximum_Iterations_Exceeded"
  int iterations = 0;
  double objective = 0;
  double constraint_violation = 0;
  double seconds = 0;
  std::vector<double> x;            // the final point (the best Ipopt has, also on failure)
  std::vector<double> multipliers;  // constraint multipliers lambda
  bool cancelled = false;           // iterationDone returned false
};

// Throws std::invalid_argument for an inconsistent program (pattern out of range, upper
// triangle Hessian entries, bounds crossing) and std::runtime_error when Ipopt cannot
// start (an option it rejects: the message names it).
IpoptResult solveWithIpopt(NonlinearProgram& program, const IpoptOptions& options = {});

}  // namespace robodiff::batch
