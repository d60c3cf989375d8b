// sim::Integrate on closed-form ODEs: if these fail, an integrator is mis-wired (wrong
// tolerances, wrong residual sign, output instants not from dense output, the last row
// not exactly at the stop time, or failures lost).
#include "sim/integrator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "tests/sim/lambda_ode.h"

namespace kanesim::sim {
namespace {


struct Rows {
  std::vector<double> t;
  std::vector<std::vector<double>> y;
  RowCallback Callback(int n) {
    return [this, n](double time, const double* state, std::string*) {
      t.push_back(time);
      y.emplace_back(state, state + n);
      return 0;
    };
  }
};

class EveryMethod : public ::testing::TestWithParam<rt::Integrator> {};

INSTANTIATE_TEST_SUITE_P(Sim, EveryMethod,
                         ::testing::Values(rt::Integrator::IDA, rt::Integrator::CvodeAdams, rt::Integrator::CvodeBdf, rt::Integrator::ArkodeErk,
                                           rt::Integrator::Dop853),
                         [](const ::testing::TestParamInfo<rt::Integrator>& param_info) {
                           std::string s = MethodName(param_info.param);
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

// Harmonic oscillator x'' = -w^2 x, x(0) = 1, x'(0) = 0: x = cos(w t), v = -w sin(w t).
TEST_P(EveryMethod, HarmonicOscillatorMatchesClosedForm) {
  constexpr double w = 2.0;
  LambdaOde ode(2, [](double, const double* y, double* yd) {
    yd[0] = y[1];
    yd[1] = -w * w * y[0];
    return 0;
  });
  const double y0[2] = {1.0, 0.0};
  Rows rows;
  IntegratorOptions opt;
  opt.method = GetParam();
  opt.rtol = opt.atol = 1e-10;
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 10.0, 0.1}, opt, rows.Callback(2));
  ASSERT_TRUE(r.ok) << r.cause;
  ASSERT_EQ(rows.t.size(), 101u);
  double max_err = 0.0;
  for (size_t k = 0; k < rows.t.size(); ++k) {
    double t = rows.t[k];
    max_err = std::max({max_err, std::abs(rows.y[k][0] - std::cos(w * t)),
                        std::abs(rows.y[k][1] + w * std::sin(w * t)) / w});
  }
  // Global error after ~3 periods: local errors of about rtol per step accumulate over a
  // few hundred (BDF, Adams) to ~2000 (explicit RK) steps: 3e3 rtol is consistent.
  constexpr double kGlobalFactor = 3e3;
  EXPECT_LT(max_err, kGlobalFactor * opt.rtol) << MethodName(GetParam()) << " steps " << r.stats.steps;
  RecordProperty("max_error", std::to_string(max_err));
  EXPECT_GT(r.stats.steps, 0);
  EXPECT_GT(r.stats.rhs_evals, 0);
}

// Exponential decay y' = -k y: the error follows the tolerance (tightening rtol by 1e4
// must shrink the error by at least 1e2), so the tolerances reach the solver.
TEST_P(EveryMethod, ExponentialDecayErrorFollowsTolerance) {
  constexpr double k = 0.7;
  LambdaOde ode(1, [](double, const double* y, double* yd) {
    yd[0] = -k * y[0];
    return 0;
  });
  const double y0[1] = {3.0};
  auto error_at = [&](double tol) {
    Rows rows;
    IntegratorOptions opt;
    opt.method = GetParam();
    opt.rtol = opt.atol = tol;
    IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 5.0, 0.05}, opt, rows.Callback(1));
    EXPECT_TRUE(r.ok) << r.cause;
    double err = 0.0;
    for (size_t i = 0; i < rows.t.size(); ++i)
      err = std::max(err, std::abs(rows.y[i][0] - 3.0 * std::exp(-k * rows.t[i])));
    return err;
  };
  double loose = error_at(1e-6), tight = error_at(1e-10);
  constexpr double kGlobalFactor = 1e2;  // monotone decay: errors do not grow
  EXPECT_LT(loose, kGlobalFactor * 1e-6 * 3.0);
  EXPECT_LT(tight, kGlobalFactor * 1e-10 * 3.0);
  // (ARKODE's rows end steps, at most 0.05 apart here: already 3e-14 off at rtol 1e-6.)
  if (GetParam() != rt::Integrator::ArkodeErk) {
    EXPECT_LT(tight, loose * 1e-2);
  }
}

// Stiff linear system y' = A y with eigenvalues -1 and -2000:
// A = [[-1000.5, 999.5], [999.5, -1000.5]], y(0) = [2, 0],
// y(t) = e^{-t} [1, 1] + e^{-2000 t} [1, -1].
LambdaOde StiffOde() {
  return LambdaOde(2, [](double, const double* y, double* yd) {
    yd[0] = -1000.5 * y[0] + 999.5 * y[1];
    yd[1] = 999.5 * y[0] - 1000.5 * y[1];
    return 0;
  });
}

IntegrateResult RunStiff(rt::Integrator m, double* max_err) {
  LambdaOde ode = StiffOde();
  const double y0[2] = {2.0, 0.0};
  Rows rows;
  IntegratorOptions opt;
  opt.method = m;
  opt.rtol = 1e-8;
  opt.atol = 1e-10;
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 10.0, 0.5}, opt, rows.Callback(2));
  *max_err = 0.0;
  for (size_t i = 0; i < rows.t.size(); ++i) {
    double t = rows.t[i], slow = std::exp(-t), fast = std::exp(-2000.0 * t);
    *max_err = std::max({*max_err, std::abs(rows.y[i][0] - (slow + fast)), std::abs(rows.y[i][1] - (slow - fast))});
  }
  return r;
}

TEST(SimStiff, ImplicitMethodsAreAccurateInFewSteps) {
  for (rt::Integrator m : {rt::Integrator::IDA, rt::Integrator::CvodeBdf}) {
    double err = 0.0;
    IntegrateResult r = RunStiff(m, &err);
    ASSERT_TRUE(r.ok) << MethodName(m) << ": " << r.cause;
    constexpr double kGlobalFactor = 1e3;  // relative to rtol on states of order 1
    EXPECT_LT(err, kGlobalFactor * 1e-8) << MethodName(m);
    // Explicit stability needs |h| < ~3/2000 for 10 s (> 6000 steps); BDF after the
    // transient steps at the accuracy of the slow mode.
    EXPECT_LT(r.stats.steps, 1500) << MethodName(m);
    EXPECT_GT(r.stats.jac_evals, 0) << MethodName(m);
    EXPECT_GT(r.stats.lin_setups, 0) << MethodName(m);
  }
  double err = 0.0;
  IntegrateResult explicit_run = RunStiff(rt::Integrator::ArkodeErk, &err);
  // The explicit method either fails (error-test failures at the stability limit) or
  // crawls: otherwise the problem is not stiff and the test proves nothing.
  EXPECT_TRUE(!explicit_run.ok || explicit_run.stats.steps > 3000) << "the test problem is not stiff";
}

// IDA's difference-quotient Jacobian evaluates f inside HoldForJacobian(true) ... (false)
// around the state it evaluated last (closed loops hold their speed partition there,
// rt::HoldPartition): every Jacobian evaluation held and no other, the holds balanced; the
// other solvers' evaluations are never held.
class HoldCountingOde final : public OdeSystem {
 public:
  int Size() const override { return 2; }
  int Rhs(double, const double* y, double* ydot) override {
    ydot[0] = y[1];
    ydot[1] = -100.0 * y[0] - 0.5 * y[1];
    (held_ ? held_evals : free_evals)++;
    if (held_ && !same_as_last(y)) ++held_far;  // a column: one component perturbed
    if (!held_) last_.assign(y, y + 2);
    return 0;
  }
  void HoldForJacobian(bool on) override {
    if (on == held_) ++unbalanced;
    held_ = on;
    if (on) ++holds;
  }
  long held_evals = 0, free_evals = 0, holds = 0, unbalanced = 0, held_far = 0;

 private:
  bool same_as_last(const double* y) const {
    int differ = 0;
    for (int i = 0; i < 2; ++i) differ += y[i] != last_[static_cast<size_t>(i)];
    return differ <= 1;
  }
  bool held_ = false;
  std::vector<double> last_{0.0, 0.0};
};

TEST(SimJacobianHold, IdaHoldsExactlyItsDifferenceQuotientEvaluations) {
  for (rt::Integrator m : {rt::Integrator::IDA, rt::Integrator::CvodeBdf, rt::Integrator::CvodeAdams, rt::Integrator::ArkodeErk, rt::Integrator::Dop853}) {
    HoldCountingOde ode;
    IntegratorOptions opt;
    opt.method = m;
    opt.rtol = opt.atol = 1e-8;
    const double y0[2] = {1.0, 0.0};
    Rows rows;
    IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 2.0, 0.1}, opt, rows.Callback(2));
    ASSERT_TRUE(r.ok) << MethodName(m) << ": " << r.cause;
    EXPECT_EQ(ode.unbalanced, 0) << MethodName(m);
    if (m == rt::Integrator::IDA) {
      EXPECT_GT(ode.holds, 0);
      EXPECT_EQ(ode.holds, r.stats.jac_evals);
      EXPECT_EQ(ode.held_evals, r.stats.rhs_evals_jac);
      EXPECT_EQ(ode.held_far, 0);
    } else {
      EXPECT_EQ(ode.holds, 0) << MethodName(m);
    }
  }
}

TEST(SimOutputGrid, RowsAreStartPlusMultiplesAndEndExactlyAtStop) {
  OutputGrid g{0.0, 1.0, 0.3};
  ASSERT_EQ(g.Count(), 5);
  EXPECT_EQ(g.Time(0), 0.0);
  EXPECT_EQ(g.Time(3), 0.3 * 3);
  EXPECT_EQ(g.Time(4), 1.0);

  OutputGrid h{0.1, 3.7, (3.7 - 0.1) / 500};
  ASSERT_EQ(h.Count(), 501);  // rounding of the interval must not add a sliver row
  EXPECT_EQ(h.Time(0), 0.1);
  EXPECT_EQ(h.Time(500), 3.7);
  for (long k = 1; k < 501; ++k) EXPECT_GT(h.Time(k), h.Time(k - 1));

  EXPECT_EQ((OutputGrid{2.0, 2.0, 0.1}.Count()), 1);
  OutputGrid tenth{0.0, 1.0, 0.1};
  ASSERT_EQ(tenth.Count(), 11);
  EXPECT_EQ(tenth.Time(3), 0.3);  // k / 10, not 3 * 0.1 = 0.30000000000000004
  EXPECT_EQ(tenth.Time(7), 0.7);
  EXPECT_EQ(tenth.Time(10), 1.0);
  EXPECT_EQ((OutputGrid{0.0, 1.0, 2.0}.Count()), 2);
}

// Many rows per internal step: the rows come from the dense output, and they are as
// accurate as the steps; first row = start with y0, last row = exactly stop.
TEST_P(EveryMethod, DenseOutputRowsMatchClosedFormBetweenSteps) {
  constexpr double w = 1.0;
  LambdaOde ode(2, [](double, const double* y, double* yd) {
    yd[0] = y[1];
    yd[1] = -w * w * y[0];
    return 0;
  });
  const double y0[2] = {0.0, 1.0};  // x = sin t
  Rows rows;
  IntegratorOptions opt;
  opt.method = GetParam();
  opt.rtol = opt.atol = 1e-9;
  const double start = 0.25, stop = 7.123456789;
  OutputGrid grid{start, stop, 0.001};
  IntegrateResult r = Integrate(ode, y0, grid, opt, rows.Callback(2));
  ASSERT_TRUE(r.ok) << r.cause;
  ASSERT_EQ(static_cast<long>(rows.t.size()), grid.Count());
  EXPECT_EQ(rows.t.front(), start);
  EXPECT_EQ(rows.y.front()[0], 0.0);
  EXPECT_EQ(rows.t.back(), stop);  // exactly, not approximately
  if (GetParam() == rt::Integrator::ArkodeErk) {  // its interpolant (degree 5) is not trusted for rows
    EXPECT_GE(r.stats.steps, static_cast<long>(rows.t.size()) - 1) << "ARKODE's rows end steps";
  } else {
    EXPECT_LT(r.stats.steps * 5, static_cast<long>(rows.t.size())) << "rows are not interpolated";
  }
  double max_err = 0.0;
  for (size_t i = 0; i < rows.t.size(); ++i) {
    double s = rows.t[i] - start;
    max_err = std::max({max_err, std::abs(rows.y[i][0] - std::sin(s)), std::abs(rows.y[i][1] - std::cos(s))});
  }
  constexpr double kGlobalFactor = 1e3;
  EXPECT_LT(max_err, kGlobalFactor * opt.rtol);
}

// A fatal right-hand side at t >= 0.5: the run stops there, says why, and every row
// before it was delivered.
TEST_P(EveryMethod, FatalRhsStopsAtItsTimeWithRowsSoFar) {
  LambdaOde ode(1, [](double t, const double* y, double* yd) {
    if (t >= 0.5) return -1;
    yd[0] = -y[0];
    return 0;
  });
  const double y0[1] = {1.0};
  Rows rows;
  IntegratorOptions opt;
  opt.method = GetParam();
  opt.max_step = 0.05;  // so that the last completed step is within 0.05 of the failure
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 1.0, 0.1}, opt, rows.Callback(1));
  ASSERT_FALSE(r.ok);
  EXPECT_GE(r.fail_time, 0.5);
  EXPECT_LT(r.fail_time, 0.5 + 0.05 + 1e-12);
  EXPECT_EQ(r.cause, "test failure cause");
  ASSERT_GE(rows.t.size(), 5u);  // 0, 0.1, ..., 0.4
  EXPECT_LT(rows.t.back(), 0.5);
  EXPECT_EQ(r.rows, static_cast<long>(rows.t.size()));
  EXPECT_NEAR(rows.y[4][0], std::exp(-0.4), 1e-4);
}

// A NaN in y' is retried as recoverable and, when it persists, fails with a cause.
TEST_P(EveryMethod, PersistentNaNFailsWithCause) {
  LambdaOde ode(1, [](double t, const double* y, double* yd) {
    yd[0] = t >= 0.5 ? std::nan("") : -y[0];
    return 0;
  });
  const double y0[1] = {1.0};
  Rows rows;
  IntegratorOptions opt;
  opt.method = GetParam();
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 1.0, 0.1}, opt, rows.Callback(1));
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.cause.find("non-finite"), std::string::npos) << r.cause;
  EXPECT_GE(r.fail_time, 0.4);
  EXPECT_LT(r.fail_time, 0.6);
}

// A row whose T + V is off the energies of the steps around it is integrated again by
// DOP853 (sim/sundials_stepper.cpp CheckRow); when that cannot succeed, the work is
// capped and the run stops at the row with the cause. Here y' = -y, T = y^2 / 2, except that
// the energy reported at the instant t = 0.5 is off by 1e6, and from then on f chatters
// (a term of +-1e3 switching every ~3e-9 s), so that DOP853 creeps. Uncapped (the run's
// 100000 steps between output instants) the re-integration takes 100000 DOP853 steps;
// capped, 4000 (1.07e5 evaluations of f with the rejected steps').
TEST(SimIntegrate, RowReintegrationThatCannotSucceedIsCappedAndStops) {
  class OffRow final : public OdeSystem {
   public:
    int Size() const override { return 1; }
    int Rhs(double t, const double* y, double* yd) override {
      yd[0] = -y[0];
      if (creep) {
        yd[0] += std::sin(1e9 * t) > 0.0 ? 1e3 : -1e3;
        ++creep_evals;
      }
      return 0;
    }
    bool ChecksSteps() const override { return true; }  // one step at a time, as with closed loops
    bool HasEnergy() const override { return true; }
    int Energy(double t, const double* y, double* T, double* V) override {
      *T = 0.5 * y[0] * y[0];
      *V = 0.0;
      if (std::fabs(t - 0.5) < 1e-14) {
        *T += 1e6;
        creep = true;
      }
      return 0;
    }
    bool creep = false;
    long creep_evals = 0;
  };
  // (Not ARKODE: its rows are step ends, no interpolant to check; sim/integrator_arkode.cpp.)
  for (rt::Integrator m : {rt::Integrator::CvodeAdams, rt::Integrator::CvodeBdf, rt::Integrator::IDA}) {
    SCOPED_TRACE(MethodName(m));
    OffRow ode;
    const double y0[1] = {1.0};
    Rows rows;
    IntegratorOptions opt;
    opt.method = m;
    opt.rtol = opt.atol = 1e-10;
    IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 1.0, 0.1}, opt, rows.Callback(1));
    ASSERT_FALSE(r.ok);
    EXPECT_NE(r.cause.find("T + V of the output instant t = 0.5"), std::string::npos) << r.cause;
    EXPECT_GE(r.fail_time, 0.5);  // the solver's time: the end of the step that holds the instant
    EXPECT_LT(r.fail_time, 0.6);
    EXPECT_EQ(r.rows, 5);  // 0 ... 0.4 kept
    EXPECT_TRUE(ode.creep);
    EXPECT_GT(ode.creep_evals, 1000);
    EXPECT_LT(ode.creep_evals, 200000);  // measured 1.07e5
    EXPECT_EQ(r.stats.energy_reject_rhs, ode.creep_evals);
  }
}

// A failing row callback (an output that cannot be evaluated) stops the run at its row.
TEST(SimIntegrate, RowFailureStopsAtThatInstant) {
  LambdaOde ode(1, [](double, const double* y, double* yd) {
    yd[0] = -y[0];
    return 0;
  });
  const double y0[1] = {1.0};
  int count = 0;
  RowCallback row = [&count](double t, const double*, std::string* cause) {
    if (t > 0.25) {
      *cause = "bad output";
      return 1;
    }
    ++count;
    return 0;
  };
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 1.0, 0.1}, IntegratorOptions{}, row);
  ASSERT_FALSE(r.ok);
  EXPECT_DOUBLE_EQ(r.fail_time, 0.3);
  EXPECT_EQ(r.cause, "bad output");
  EXPECT_EQ(count, 3);
  EXPECT_EQ(r.rows, 3);
}

// IDA evaluates f at t0 for a consistent y'(t0): a failure there is reported at t0.
TEST(SimIntegrate, IdaFailureAtStartIsReportedAtStart) {
  LambdaOde ode(1, [](double, const double*, double*) { return -1; });
  const double y0[1] = {1.0};
  Rows rows;
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 1.0, 0.1}, IntegratorOptions{}, rows.Callback(1));
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.fail_time, 0.0);
  EXPECT_EQ(r.cause, "test failure cause");
  EXPECT_EQ(rows.t.size(), 1u);
}

}  // namespace
}  // namespace kanesim::sim
