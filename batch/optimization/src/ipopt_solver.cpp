// solveWithIpopt: a NonlinearProgram behind Ipopt's TNLP interface.
#include "robodiff/batch/ipopt_solver.hpp"

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <string>

namespace robodiff::batch {
namespace {

using Ipopt::Index;
using Ipopt::Number;

constexpr double kIpoptInfinity = 1e20;  // beyond Ipopt's default +-1e19: "no bound"

double toIpoptBound(double b) {
  if (std::isinf(b)) return b > 0 ? kIpoptInfinity : -kIpoptInfinity;
  return b;
}

const char* statusName(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found: return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option: return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception: return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown: return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory: return "Insufficient_Memory";
    case Ipopt::Internal_Error: return "Internal_Error";
  }
  return "Unknown";
}

// Checks a pattern once: in range, and lower triangle for the Hessian.
void checkPattern(const SparsityEntries& entries, int rows, int cols, bool lower, const char* what) {
  for (const auto& [r, c] : entries) {
    if (r < 0 || r >= rows || c < 0 || c >= cols)
      throw std::invalid_argument(std::string(what) + " pattern entry (" + std::to_string(r) + ", " +
                                  std::to_string(c) + ") is outside " + std::to_string(rows) + " x " +
                                  std::to_string(cols));
    if (lower && c > r)
      throw std::invalid_argument(std::string(what) + " pattern entry (" + std::to_string(r) + ", " +
                                  std::to_string(c) + ") is above the diagonal: give the lower triangle");
  }
}

class ProgramAdapter final : public Ipopt::TNLP {
 public:
  ProgramAdapter(NonlinearProgram& program, IpoptResult& result)
      : program_(program), result_(result), n_(program.variableCount()), m_(program.constraintCount()),
        jacobian_(program.constraintJacobianPattern()), hessian_(program.hessianPattern()) {
    checkPattern(jacobian_, m_, n_, false, "constraint Jacobian");
    checkPattern(hessian_, n_, n_, true, "Hessian");
  }

  std::exception_ptr error;  // thrown by the program inside a callback, rethrown after

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& style) override {
    n = n_;
    m = m_;
    nnz_jac_g = static_cast<Index>(jacobian_.size());
    nnz_h_lag = static_cast<Index>(hessian_.size());
    style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    return guarded([&] {
      program_.bounds({x_l, static_cast<std::size_t>(n)}, {x_u, static_cast<std::size_t>(n)},
                      {g_l, static_cast<std::size_t>(m)}, {g_u, static_cast<std::size_t>(m)});
      auto convert = [](Number* lo, Number* hi, Index k, const char* what) {
        for (Index i = 0; i < k; ++i) {
          if (lo[i] > hi[i])
            throw std::invalid_argument(std::string(what) + " " + std::to_string(i) + ": lower bound " +
                                        std::to_string(lo[i]) + " above upper bound " + std::to_string(hi[i]));
          lo[i] = toIpoptBound(lo[i]);
          hi[i] = toIpoptBound(hi[i]);
        }
      };
      convert(x_l, x_u, n, "variable");
      convert(g_l, g_u, m, "constraint");
    });
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    return guarded([&] {
      if (init_x) program_.startingPoint({x, static_cast<std::size_t>(n)});
    });
  }

  bool eval_f(Index n, const Number* x, bool, Number& value) override {
    return guarded([&] { value = program_.objective({x, static_cast<std::size_t>(n)}); });
  }

  bool eval_grad_f(Index n, const Number* x, bool, Number* grad) override {
    return guarded([&] { program_.gradient({x, static_cast<std::size_t>(n)}, {grad, static_cast<std::size_t>(n)}); });
  }

  bool eval_g(Index n, const Number* x, bool, Index m, Number* g) override {
    return guarded([&] { program_.constraints({x, static_cast<std::size_t>(n)}, {g, static_cast<std::size_t>(m)}); });
  }

  bool eval_jac_g(Index n, const Number* x, bool, Index, Index nele, Index* rows, Index* cols,
                  Number* values) override {
    return guarded([&] {
      if (values == nullptr) {
        for (Index k = 0; k < nele; ++k) {
          rows[k] = jacobian_[k].first;
          cols[k] = jacobian_[k].second;
        }
      } else {
        program_.constraintJacobian({x, static_cast<std::size_t>(n)}, {values, static_cast<std::size_t>(nele)});
      }
    });
  }

  bool eval_h(Index n, const Number* x, bool, Number sigma, Index m, const Number* lambda, bool, Index nele,
              Index* rows, Index* cols, Number* values) override {
    return guarded([&] {
      if (values == nullptr) {
        for (Index k = 0; k < nele; ++k) {
          rows[k] = hessian_[k].first;
          cols[k] = hessian_[k].second;
        }
      } else {
        program_.hessian({x, static_cast<std::size_t>(n)}, sigma, {lambda, static_cast<std::size_t>(m)},
                         {values, static_cast<std::size_t>(nele)});
      }
    });
  }

  void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*, const Number*, Index m,
                         const Number* g, const Number* lambda, Number objective, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    result_.x.assign(x, x + n);
    result_.multipliers.assign(lambda, lambda + m);
    result_.objective = objective;
    // The largest violation of a constraint or variable bound at the final point.
    double violation = 0;
    std::vector<double> xl(n), xu(n), gl(m), gu(m);
    program_.bounds(xl, xu, gl, gu);
    for (Index i = 0; i < m; ++i) violation = std::max({violation, gl[i] - g[i], g[i] - gu[i]});
    for (Index i = 0; i < n; ++i) violation = std::max({violation, xl[i] - x[i], x[i] - xu[i]});
    result_.constraint_violation = violation;
  }

  bool intermediate_callback(Ipopt::AlgorithmMode, Index iteration, Number objective, Number inf_pr, Number inf_du,
                             Number mu, Number, Number, Number, Number, Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    bool go_on = true;
    const bool ok = guarded([&] {
      IterationInfo info;
      info.iteration = iteration;
      info.objective = objective;
      info.primal_infeasibility = inf_pr;
      info.dual_infeasibility = inf_du;
      info.barrier = mu;
      go_on = program_.iterationDone(info);
    });
    if (!go_on) result_.cancelled = true;
    return ok && go_on;
  }

 private:
  // Runs a program call; an exception is kept (Ipopt sees a failed evaluation and stops).
  template <class Call>
  bool guarded(Call call) {
    if (error) return false;
    try {
      call();
      return true;
    } catch (...) {
      error = std::current_exception();
      return false;
    }
  }

  NonlinearProgram& program_;
  IpoptResult& result_;
  int n_, m_;
  SparsityEntries jacobian_, hessian_;
};

void setOption(Ipopt::IpoptApplication& app, const std::string& name, const std::string& value) {
  // Ipopt options are typed: try a whole number, then a real, then text.
  char* end = nullptr;
  const long integer = std::strtol(value.c_str(), &end, 10);
  bool ok = false;
  if (!value.empty() && *end == '\0') {
    ok = app.Options()->SetIntegerValue(name, static_cast<Index>(integer)) ||
         app.Options()->SetNumericValue(name, static_cast<Number>(integer));
  } else {
    const double real = std::strtod(value.c_str(), &end);
    if (!value.empty() && *end == '\0')
      ok = app.Options()->SetNumericValue(name, real);
    else
      ok = app.Options()->SetStringValue(name, value);
  }
  if (!ok) throw std::runtime_error("Ipopt rejected the option " + name + " = '" + value + "'");
}

}  // namespace

IpoptResult solveWithIpopt(NonlinearProgram& program, const IpoptOptions& options) {
  IpoptResult result;
  Ipopt::SmartPtr<ProgramAdapter> adapter = new ProgramAdapter(program, result);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->RethrowNonIpoptException(false);
  setOption(*app, "sb", "yes");  // no banner
  setOption(*app, "print_level", std::to_string(options.print_level));
  setOption(*app, "max_iter", std::to_string(options.max_iterations));
  app->Options()->SetNumericValue("tol", options.tolerance);
  app->Options()->SetNumericValue("acceptable_tol", options.acceptable_tolerance);
  if (options.max_seconds > 0) app->Options()->SetNumericValue("max_cpu_time", options.max_seconds);
  app->Options()->SetStringValue("hessian_approximation", options.exact_hessian ? "exact" : "limited-memory");
  if (!options.derivative_test.empty()) setOption(*app, "derivative_test", options.derivative_test);
  for (const auto& [name, value] : options.extra) setOption(*app, name, value);

  const Ipopt::ApplicationReturnStatus init = app->Initialize();
  if (init != Ipopt::Solve_Succeeded)
    throw std::runtime_error(std::string("Ipopt could not start: ") + statusName(init));

  const auto start = std::chrono::steady_clock::now();
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(GetRawPtr(adapter)));
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (adapter->error) std::rethrow_exception(adapter->error);
  result.status = statusName(status);
  result.success = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  if (status == Ipopt::Invalid_Option) throw std::runtime_error("Ipopt: an option was not accepted (Invalid_Option)");
  if (Ipopt::IsValid(app->Statistics())) result.iterations = app->Statistics()->IterationCount();
  return result;
}

}  // namespace robodiff::batch
