#include "ipopt_nlp.hpp"

#include <cmath>
#include <limits>
#include <mutex>

#include "IpIpoptApplication.hpp"
#include "IpSolveStatistics.hpp"
#include "IpTNLP.hpp"

namespace orthomech::solvers {

namespace {

using Ipopt::Index;
using Ipopt::Number;

// The TNLP: dense Jacobian (row-major, every entry) and dense lower triangle of the Hessian.
// Every callback goes through guard(): a std::exception (or anything else) is stored and Ipopt
// is told the evaluation failed, so nothing is thrown through Ipopt's C++/Fortran frames.
class DenseTnlp : public Ipopt::TNLP {
 public:
  DenseTnlp(const DenseNlp& nlp, const IpoptSettings& settings, IpoptOutcome& out)
      : nlp_(nlp),
        settings_(settings),
        out_(out),
        x_(nlp.n),
        v_(nlp.n),
        g_(nlp.m),
        J_(nlp.m, nlp.n),
        H_(nlp.n, nlp.n),
        lambda_(nlp.m) {}

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override {
    n = nlp_.n;
    m = nlp_.m;
    nnz_jac_g = nlp_.n * nlp_.m;
    nnz_h_lag = nlp_.n * (nlp_.n + 1) / 2;
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l,
                       Number* g_u) override {
    for (Index i = 0; i < n; ++i) {
      x_l[i] = finite_or(nlp_.x_lower, i, -kInf);
      x_u[i] = finite_or(nlp_.x_upper, i, kInf);
    }
    for (Index i = 0; i < m; ++i) {
      g_l[i] = finite_or(nlp_.g_lower, i, -kInf);
      g_u[i] = finite_or(nlp_.g_upper, i, kInf);
    }
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number*, Number*, Index,
                          bool init_lambda, Number*) override {
    if (!init_x || init_z || init_lambda) return false;
    for (Index i = 0; i < n; ++i) x[i] = nlp_.x0(i);
    return true;
  }

  bool eval_f(Index n, const Number* x, bool, Number& obj_value) override {
    return guard([&] {
      load(n, x);
      obj_value = nlp_.objective(x_);
      return std::isfinite(obj_value);
    });
  }

  bool eval_grad_f(Index n, const Number* x, bool, Number* grad_f) override {
    return guard([&] {
      load(n, x);
      v_.setZero();
      nlp_.gradient(x_, v_);
      for (Index i = 0; i < n; ++i) grad_f[i] = v_(i);
      return v_.allFinite();
    });
  }

  bool eval_g(Index n, const Number* x, bool, Index m, Number* g) override {
    return guard([&] {
      load(n, x);
      g_.setZero();
      nlp_.constraints(x_, g_);
      for (Index i = 0; i < m; ++i) g[i] = g_(i);
      return g_.allFinite();
    });
  }

  bool eval_jac_g(Index n, const Number* x, bool, Index m, Index, Index* iRow, Index* jCol,
                  Number* values) override {
    return guard([&] {
      if (!values) {
        Index k = 0;
        for (Index i = 0; i < m; ++i)
          for (Index j = 0; j < n; ++j, ++k) {
            iRow[k] = i;
            jCol[k] = j;
          }
        return true;
      }
      load(n, x);
      J_.setZero();
      nlp_.jacobian(x_, J_);
      Index k = 0;
      for (Index i = 0; i < m; ++i)
        for (Index j = 0; j < n; ++j, ++k) values[k] = J_(i, j);
      return J_.allFinite();
    });
  }

  bool eval_h(Index n, const Number* x, bool, Number obj_factor, Index m, const Number* lambda,
              bool, Index, Index* iRow, Index* jCol, Number* values) override {
    return guard([&] {
      if (!values) {
        Index k = 0;
        for (Index i = 0; i < n; ++i)
          for (Index j = 0; j <= i; ++j, ++k) {
            iRow[k] = i;
            jCol[k] = j;
          }
        return true;
      }
      load(n, x);
      for (Index i = 0; i < m; ++i) lambda_(i) = lambda[i];
      H_.setZero();
      nlp_.hessian(x_, obj_factor, lambda_, H_);
      Index k = 0;
      for (Index i = 0; i < n; ++i)
        for (Index j = 0; j <= i; ++j, ++k) values[k] = H_(i, j);
      return H_.allFinite();
    });
  }

  void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*,
                         const Number*, Index m, const Number*, const Number* lambda,
                         Number obj_value, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    if (x) {
      out_.x.resize(n);
      for (Index i = 0; i < n; ++i) out_.x(i) = x[i];
    }
    if (lambda) {
      out_.lambda.resize(m);
      for (Index i = 0; i < m; ++i) out_.lambda(i) = lambda[i];
    }
    out_.objective = obj_value;
  }

  bool intermediate_callback(Ipopt::AlgorithmMode, Index iter, Number, Number, Number, Number,
                             Number, Number, Number, Number, Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    out_.iterations = iter;
    if (out_.error) return false;  // a stored exception stops the solve (User_Requested_Stop)
    if (settings_.keep_going && !guard([&] { return settings_.keep_going(iter); })) {
      stopped_ = !out_.error;
      return false;
    }
    return true;
  }
  [[nodiscard]] bool stopped_by_caller() const { return stopped_; }

 private:
  static constexpr double kInf = 1e20;  // Ipopt's default nlp_lower/upper_bound_inf

  static double finite_or(const Eigen::VectorXd& v, Index i, double fallback) {
    if (v.size() == 0 || !std::isfinite(v(i))) return fallback;
    return v(i);
  }
  void load(Index n, const Number* x) {
    for (Index i = 0; i < n; ++i) x_(i) = x[i];
  }
  template <typename F>
  bool guard(F&& f) {
    if (out_.error) return false;
    try {
      return f();
    } catch (...) {
      out_.error = std::current_exception();
      return false;
    }
  }

  const DenseNlp& nlp_;
  const IpoptSettings& settings_;
  IpoptOutcome& out_;
  bool stopped_ = false;  // keep_going said stop
  Eigen::VectorXd x_, v_, g_;
  Eigen::MatrixXd J_, H_;
  Eigen::VectorXd lambda_;
};

IpoptOutcomeKind classify(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded:
      return IpoptOutcomeKind::solved;
    case Ipopt::Solved_To_Acceptable_Level:
    case Ipopt::Feasible_Point_Found:
      return IpoptOutcomeKind::acceptable;
    case Ipopt::Infeasible_Problem_Detected:
      return IpoptOutcomeKind::infeasible;
    case Ipopt::Search_Direction_Becomes_Too_Small:
    case Ipopt::Diverging_Iterates:
    case Ipopt::Maximum_Iterations_Exceeded:
    case Ipopt::Maximum_CpuTime_Exceeded:
    case Ipopt::Restoration_Failed:
    case Ipopt::Error_In_Step_Computation:
    case Ipopt::User_Requested_Stop:
      return IpoptOutcomeKind::not_converged;
    case Ipopt::Not_Enough_Degrees_Of_Freedom:
      return IpoptOutcomeKind::too_few_dof;
    case Ipopt::Invalid_Number_Detected:
      return IpoptOutcomeKind::invalid_number;
    default:
      return IpoptOutcomeKind::failed;
  }
}

const char* status_name(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded:
      return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level:
      return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected:
      return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small:
      return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates:
      return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop:
      return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found:
      return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded:
      return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed:
      return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation:
      return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded:
      return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom:
      return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition:
      return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option:
      return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected:
      return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception:
      return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown:
      return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory:
      return "Insufficient_Memory";
    case Ipopt::Internal_Error:
      return "Internal_Error";
  }
  return "unknown";
}

}  // namespace

const char* to_string(IpoptOutcomeKind k) {
  switch (k) {
    case IpoptOutcomeKind::solved:
      return "solved";
    case IpoptOutcomeKind::acceptable:
      return "acceptable";
    case IpoptOutcomeKind::infeasible:
      return "infeasible";
    case IpoptOutcomeKind::not_converged:
      return "not converged";
    case IpoptOutcomeKind::too_few_dof:
      return "too few degrees of freedom";
    case IpoptOutcomeKind::invalid_number:
      return "invalid number";
    case IpoptOutcomeKind::stopped:
      return "stopped";
    case IpoptOutcomeKind::callback_error:
      return "callback error";
    case IpoptOutcomeKind::failed:
      return "failed";
  }
  return "?";
}

IpoptOutcome solve_with_ipopt(const DenseNlp& nlp, const IpoptSettings& settings) {
  // One solve at a time in the process, from the application's creation to its destruction (which
  // ends MUMPS): Debian's Ipopt factors with the sequential MUMPS, whose Fortran module state is
  // process-wide; two solves on two threads (a design study's validate and assemble metrics on
  // every core) corrupt it ("PB allocation in DMUMPS_LOAD_INIT").
  static std::mutex mumps;
  const std::lock_guard<std::mutex> one_at_a_time(mumps);
  IpoptOutcome out;
  out.x = nlp.x0;
  out.lambda = Eigen::VectorXd::Zero(nlp.m);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  // Initialize("") so that no ./ipopt.opt overrides these options (docs: dependencies).
  Ipopt::OptionsList& o = *app->Options();
  o.SetStringValue("sb", "yes");  // no licence banner (print_level 0 alone does not do it)
  o.SetIntegerValue("print_level", 0);
  o.SetNumericValue("tol", settings.tol);
  o.SetNumericValue("constr_viol_tol", settings.constr_viol_tol);
  o.SetIntegerValue("max_iter", settings.max_iter);
  o.SetNumericValue("max_cpu_time", settings.max_cpu_time);
  if (!nlp.hessian) o.SetStringValue("hessian_approximation", "limited-memory");
  Ipopt::ApplicationReturnStatus status = app->Initialize(std::string(""));
  if (status != Ipopt::Solve_Succeeded) {
    out.code = static_cast<int>(status);
    out.status = status_name(status);
    out.kind = IpoptOutcomeKind::failed;
    out.message = "Ipopt could not be initialised";
    return out;
  }
  auto* dense = new DenseTnlp(nlp, settings, out);
  Ipopt::SmartPtr<Ipopt::TNLP> tnlp = dense;
  try {
    status = app->OptimizeTNLP(tnlp);
  } catch (...) {  // Ipopt catches its own; this is belt and braces
    out.error = std::current_exception();
    status = Ipopt::NonIpopt_Exception_Thrown;
  }
  out.code = static_cast<int>(status);
  out.status = status_name(status);
  out.kind = out.error                    ? IpoptOutcomeKind::callback_error
             : dense->stopped_by_caller() ? IpoptOutcomeKind::stopped
                                          : classify(status);
  if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics(); Ipopt::IsValid(stats))
    out.iterations = stats->IterationCount();
  if (out.error) {
    try {
      std::rethrow_exception(out.error);
    } catch (const std::exception& e) {
      out.message = std::string("a callback threw: ") + e.what();
    } catch (...) {
      out.message = "a callback threw a non-standard exception";
    }
  } else {
    out.message = std::string("Ipopt: ") + out.status;
  }
  return out;
}

}  // namespace orthomech::solvers
