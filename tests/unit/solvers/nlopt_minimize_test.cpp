// The private NLopt adapter (src/solvers/nlopt_minimize.cpp): every failure mode comes back as a
// status, and an exception thrown by the objective never crosses the solver (it is stored and
// reported). Oracles: closed-form minimisers of small problems.
#include "../../../src/solvers/nlopt_minimize.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace orthomech::solvers {
namespace {

using Eigen::VectorXd;

TEST(NloptAdapter, Converged_ClosedForm) {
  const auto f = [](const VectorXd& x) { return std::pow(x(0) - 0.3, 2) + 1.0; };
  const NloptOutcome r = minimize_bounded(f, VectorXd::Constant(1, 0.9), VectorXd::Constant(1, 0.0),
                                          VectorXd::Constant(1, 1.0));
  EXPECT_EQ(r.kind, NloptOutcomeKind::converged) << r.message;
  EXPECT_NEAR(r.x(0), 0.3, 1e-6);
  EXPECT_NEAR(r.value, 1.0, 1e-12);
}

TEST(NloptAdapter, Bounded2D_ClosedForm) {
  // Minimum of (x − 2)² + (y + 1)² on [0, 1]²: the corner (1, 0).
  const auto f = [](const VectorXd& x) { return std::pow(x(0) - 2, 2) + std::pow(x(1) + 1, 2); };
  const NloptOutcome r =
      minimize_bounded(f, VectorXd::Constant(2, 0.5), VectorXd::Zero(2), VectorXd::Ones(2));
  EXPECT_EQ(r.kind, NloptOutcomeKind::converged) << r.message;
  EXPECT_NEAR(r.x(0), 1.0, 1e-8);
  EXPECT_NEAR(r.x(1), 0.0, 1e-8);
}

TEST(NloptAdapter, ThrowingObjective_StoredNotPropagated) {
  int calls = 0;
  const auto f = [&calls](const VectorXd& x) {
    if (++calls > 3) throw std::logic_error("boom in the objective");
    return x(0) * x(0);
  };
  NloptOutcome r;
  EXPECT_NO_THROW(r = minimize_bounded(f, VectorXd::Constant(1, 0.5), VectorXd::Constant(1, -1.0),
                                       VectorXd::Constant(1, 1.0)));
  EXPECT_EQ(r.kind, NloptOutcomeKind::callback_error);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.message.find("boom in the objective"), std::string::npos);
}

TEST(NloptAdapter, NaN_InvalidBounds_EvaluationLimit_AreStatuses) {
  const auto nan = [](const VectorXd&) { return std::numeric_limits<double>::quiet_NaN(); };
  EXPECT_EQ(minimize_bounded(nan, VectorXd::Constant(1, 0.5), VectorXd::Constant(1, 0.0),
                             VectorXd::Constant(1, 1.0))
                .kind,
            NloptOutcomeKind::callback_error);
  const auto sq = [](const VectorXd& x) { return x.squaredNorm(); };
  EXPECT_EQ(minimize_bounded(sq, VectorXd::Constant(1, 0.5), VectorXd::Constant(1, 1.0),
                             VectorXd::Constant(1, 0.0))
                .kind,
            NloptOutcomeKind::invalid);
  NloptSettings s;
  s.max_evaluations = 3;
  s.xtol_abs = 0.0;
  const auto wavy = [](const VectorXd& x) { return std::sin(20 * x(0)) + x(0) * x(0); };
  EXPECT_EQ(minimize_bounded(wavy, VectorXd::Constant(1, 0.5), VectorXd::Constant(1, -1.0),
                             VectorXd::Constant(1, 1.0), s)
                .kind,
            NloptOutcomeKind::max_evaluations);
}

// Multistart (issue 50): the global minimum of a 2-D function with many local minima, found
// from the quasi-random design; oracle: the minimiser by hand. f = Σ (x_i² − 10 cos 2πx_i) + 20
// (Rastrigin) has its global minimum 0 at the origin and a local minimum near every integer point.
TEST(NloptAdapter, Multistart_FindsTheGlobalMinimumOfRastrigin) {
  const auto f = [](const VectorXd& x) {
    double v = 20.0;
    for (int i = 0; i < 2; ++i) v += x(i) * x(i) - 10.0 * std::cos(2.0 * std::numbers::pi * x(i));
    return v;
  };
  MultistartSettings s;
  s.starts = 200;
  s.seed = 7;
  const MultistartOutcome r =
      minimize_multistart(f, VectorXd::Constant(2, -4.2), VectorXd::Constant(2, 4.7), s);
  EXPECT_EQ(r.best.kind, NloptOutcomeKind::converged) << r.best.message;
  EXPECT_NEAR(r.best.x(0), 0.0, 1e-6);
  EXPECT_NEAR(r.best.x(1), 0.0, 1e-6);
  EXPECT_EQ(r.locals.size(), 200U);
  // Deterministic: the same seed gives the same runs, another seed other starts.
  const MultistartOutcome again =
      minimize_multistart(f, VectorXd::Constant(2, -4.2), VectorXd::Constant(2, 4.7), s);
  EXPECT_EQ(again.evaluations, r.evaluations);
  EXPECT_EQ(again.best.x, r.best.x);
}

// On several threads, each with its own objective (and its own scratch: a counter here, which a
// shared objective would race on), the outcome is the one-thread outcome run for run.
TEST(NloptAdapter, Multistart_SameOutcomeOnAnyThreadCount) {
  const auto make = [] {
    return [calls = 0L](const VectorXd& x) mutable {
      ++calls;
      double v = 20.0;
      for (int i = 0; i < 2; ++i) v += x(i) * x(i) - 10.0 * std::cos(2.0 * std::numbers::pi * x(i));
      return v;
    };
  };
  MultistartSettings s;
  s.starts = 64;
  s.seed = 3;
  s.threads = 1;
  const MultistartOutcome one =
      minimize_multistart(make, VectorXd::Constant(2, -4.2), VectorXd::Constant(2, 4.7), s);
  for (const int threads : {2, 3, 0}) {
    s.threads = threads;
    const MultistartOutcome many =
        minimize_multistart(make, VectorXd::Constant(2, -4.2), VectorXd::Constant(2, 4.7), s);
    EXPECT_EQ(many.evaluations, one.evaluations) << threads;
    EXPECT_EQ(many.best.x, one.best.x) << threads;
    ASSERT_EQ(many.locals.size(), one.locals.size());
    for (size_t k = 0; k < one.locals.size(); ++k) {
      EXPECT_EQ(many.locals[k].x, one.locals[k].x) << threads << " run " << k;
      EXPECT_EQ(many.locals[k].value, one.locals[k].value) << threads << " run " << k;
    }
  }
}

// Shared among processes (ProcessShare, as under mpirun): process r of 3 runs the starts
// k = r, r + 3, … and gathers the others. The test plays each process in turn: its gather checks
// that the process sent exactly its own runs of the one-process outcome (record [kind, code,
// value, evaluations, x]) and hands back the other processes' records, packed here from that
// outcome; the assembled outcome is the one-process outcome run for run.
TEST(NloptAdapter, Multistart_SharedAmongProcessesIsTheOneProcessOutcome) {
  const auto f = [](const VectorXd& x) {
    double v = 20.0;
    for (int i = 0; i < 2; ++i) v += x(i) * x(i) - 10.0 * std::cos(2.0 * std::numbers::pi * x(i));
    return v;
  };
  MultistartSettings s;
  s.starts = 17;  // not a multiple of 3: the processes hold 6, 6 and 5 runs
  s.seed = 5;
  const VectorXd lo = VectorXd::Constant(2, -4.2), hi = VectorXd::Constant(2, 4.7);
  const MultistartOutcome one = minimize_multistart(f, lo, hi, s);
  const int runs = static_cast<int>(one.locals.size());
  const auto record = [&](int k) {
    const NloptOutcome& o = one.locals[static_cast<size_t>(k)];
    return std::vector<double>{static_cast<double>(o.kind),
                               static_cast<double>(o.code),
                               o.value,
                               static_cast<double>(o.evaluations),
                               o.x(0),
                               o.x(1)};
  };
  for (int rank = 0; rank < 3; ++rank) {
    s.share.rank = rank;
    s.share.size = 3;
    s.share.gather = [&](const std::vector<double>& mine, const std::vector<int>& counts) {
      std::vector<double> all, own;
      for (int r = 0; r < 3; ++r) {
        int n = 0;
        for (int k = r; k < runs; k += 3, n += 6) {
          const std::vector<double> rec = record(k);
          all.insert(all.end(), rec.begin(), rec.end());
          if (r == rank) own.insert(own.end(), rec.begin(), rec.end());
        }
        EXPECT_EQ(counts[static_cast<size_t>(r)], n) << "rank " << r;
      }
      EXPECT_EQ(mine, own) << "process " << rank << " ran other starts than k = r mod 3";
      return all;
    };
    const MultistartOutcome shared = minimize_multistart(f, lo, hi, s);
    EXPECT_EQ(shared.evaluations, one.evaluations) << rank;
    EXPECT_EQ(shared.best.x, one.best.x) << rank;
    ASSERT_EQ(shared.locals.size(), one.locals.size());
    for (int k = 0; k < runs; ++k) {
      EXPECT_EQ(shared.locals[static_cast<size_t>(k)].x, one.locals[static_cast<size_t>(k)].x);
      EXPECT_EQ(shared.locals[static_cast<size_t>(k)].value,
                one.locals[static_cast<size_t>(k)].value);
    }
  }
}

TEST(NloptAdapter, QuasiRandomStartsFillTheBoxAndFollowTheSeed) {
  const VectorXd lo = VectorXd::Constant(3, -1.0), hi = VectorXd::Constant(3, 2.0);
  const Eigen::MatrixXd X = quasi_random_starts(lo, hi, 64, 3);
  ASSERT_EQ(X.cols(), 64);
  EXPECT_GE(X.minCoeff(), -1.0);
  EXPECT_LT(X.maxCoeff(), 2.0);
  // Every eighth of each axis holds a point (a low-discrepancy set, unlike 64 clumped draws).
  for (int i = 0; i < 3; ++i)
    for (int bin = 0; bin < 8; ++bin) {
      bool hit = false;
      for (int k = 0; k < 64; ++k) hit = hit || static_cast<int>((X(i, k) + 1.0) / 3.0 * 8) == bin;
      EXPECT_TRUE(hit) << "axis " << i << " bin " << bin;
    }
  EXPECT_EQ(quasi_random_starts(lo, hi, 64, 3), X);
  EXPECT_NE(quasi_random_starts(lo, hi, 64, 4), X);
}

TEST(NloptAdapter, Multistart_StopsAtTheFirstCallbackError) {
  const auto f = [](const VectorXd&) -> double { throw std::runtime_error("boom"); };
  MultistartSettings s;
  s.starts = 10;
  const MultistartOutcome r =
      minimize_multistart(f, VectorXd::Constant(2, -1.0), VectorXd::Constant(2, 1.0), s);
  EXPECT_EQ(r.best.kind, NloptOutcomeKind::callback_error);
  EXPECT_EQ(r.locals.size(), 1U);
}

}  // namespace
}  // namespace orthomech::solvers
