#pragma once
// Private adapter (house style: no Ipopt type in a public header): a dense nonlinear program
//   min φ(x)  subject to  g_l ≤ g(x) ≤ g_u,  x_l ≤ x ≤ x_u
// described by std::function callbacks on Eigen vectors, solved with Ipopt's interior-point
// method. Every outcome of Ipopt is returned as data (IpoptOutcome); an exception thrown by a
// callback never crosses Ipopt: it is caught in the callback, stored in `error`, the solve is
// stopped (the callback returns false), and the caller decides (assembly rethrows it after the
// solve).
#include <Eigen/Core>
#include <exception>
#include <functional>
#include <string>

namespace orthomech::solvers {

struct DenseNlp {
  int n = 0;                                               // variables
  int m = 0;                                               // constraints
  Eigen::VectorXd x0, x_lower, x_upper, g_lower, g_upper;  // ±inf (or ±1e20) when unbounded
  std::function<double(const Eigen::VectorXd& x)> objective;
  std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& grad)> gradient;
  std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& g)> constraints;
  std::function<void(const Eigen::VectorXd& x, Eigen::MatrixXd& J)> jacobian;  // m × n, dense
  // σ ∇²φ + Σ λ_i ∇²g_i, full symmetric n × n (only the lower triangle is passed on). When
  // empty, Ipopt's limited-memory quasi-Newton approximation is used.
  std::function<void(const Eigen::VectorXd& x, double sigma, const Eigen::VectorXd& lambda,
                     Eigen::MatrixXd& H)>
      hessian;
};

struct IpoptSettings {
  double tol = 1e-10;              // Ipopt `tol` (scaled NLP error)
  double constr_viol_tol = 1e-12;  // Ipopt `constr_viol_tol`
  int max_iter = 200;
  double max_cpu_time = 60.0;  // s
  // Asked after every iteration (its number): false stops the solve with outcome `stopped` (the
  // caller's run bounds: a time limit, SIGINT/SIGTERM). Empty: never stops.
  std::function<bool(int iteration)> keep_going;
};

enum class IpoptOutcomeKind {
  solved,          // Solve_Succeeded
  acceptable,      // Solved_To_Acceptable_Level
  infeasible,      // Infeasible_Problem_Detected (local infeasibility)
  not_converged,   // iteration/time limit, step too small, restoration failed, diverging
  too_few_dof,     // Not_Enough_Degrees_Of_Freedom
  invalid_number,  // NaN/Inf from a callback or a callback returned false
  stopped,         // IpoptSettings::keep_going said stop (User_Requested_Stop)
  callback_error,  // a callback threw: see `error`
  failed,          // any other Ipopt error (invalid problem, option, internal error)
};

struct IpoptOutcome {
  IpoptOutcomeKind kind = IpoptOutcomeKind::failed;
  int code = 0;            // Ipopt's ApplicationReturnStatus
  std::string status;      // Ipopt's name for it, e.g. "Solve_Succeeded"
  std::string message;     // ours, in words
  Eigen::VectorXd x;       // final iterate (the starting point if Ipopt never produced one)
  Eigen::VectorXd lambda;  // constraint multipliers (Ipopt's sign: ∇φ + Jᵀλ − z = 0)
  double objective = 0.0;
  int iterations = 0;
  std::exception_ptr error;  // exception thrown by a callback, if any
};

// Never throws for anything Ipopt or a callback does (std::bad_alloc aside).
[[nodiscard]] IpoptOutcome solve_with_ipopt(const DenseNlp& nlp, const IpoptSettings& settings);

[[nodiscard]] const char* to_string(IpoptOutcomeKind k);

}  // namespace orthomech::solvers
