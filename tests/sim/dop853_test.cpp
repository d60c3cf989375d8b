// Our DOP853 (sim/integrator_dop853.cpp) on closed-form ODEs and on the double
// pendulum through the public runtime. If these fail, the tableau or its use is wrong
// (order below 8, dense output below 7), the step control ignores the tolerance, the
// FSAL / dense-output bookkeeping wastes or skips evaluations of f, the stop time is
// overstepped, or failures of f are lost.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "sim/integrator.h"
#include "tests/support/load_util.h"

#include "tests/sim/lambda_ode.h"

namespace kanesim::sim {
namespace {


// x'' = -w^2 x, x(0) = 1, x'(0) = 0: x = cos(w t), x' = -w sin(w t).
constexpr double kW = 2.0;
LambdaOde Oscillator() {
  return LambdaOde(2, [](double, const double* y, double* yd) {
    yd[0] = y[1];
    yd[1] = -kW * kW * y[0];
    return 0;
  });
}
double OscillatorError(double t, const double* y) {
  return std::max(std::abs(y[0] - std::cos(kW * t)), std::abs(y[1] + kW * std::sin(kW * t)) / kW);
}

// Largest error over the rows of one run, with its stats.
struct OscRun {
  IntegrateResult result;
  double max_err = 0.0;
  double end_err = 0.0;
  long rows = 0;
};

OscRun RunOscillator(double stop, double interval, IntegratorOptions opt) {
  LambdaOde ode = Oscillator();
  const double y0[2] = {1.0, 0.0};
  opt.method = rt::Integrator::Dop853;
  OscRun run;
  RowCallback cb = [&run](double t, const double* y, std::string*) {
    run.end_err = OscillatorError(t, y);
    run.max_err = std::max(run.max_err, run.end_err);
    ++run.rows;
    return 0;
  };
  run.result = Integrate(ode, y0, OutputGrid{0.0, stop, interval}, opt, cb);
  EXPECT_EQ(run.result.stats.rhs_evals, ode.evals) << "Stats() must count every evaluation of f";
  return run;
}

// With fixed steps (max_step = initial_step = h, a tolerance too loose to reject), halving
// h divides the global error by 2^8 = 256 for an 8th-order method (7th order: 128).
TEST(SimDop853, FixedStepGlobalErrorConvergesAtEighthOrder) {
  double err[2];
  const double h[2] = {0.2, 0.1};
  for (int k = 0; k < 2; ++k) {
    IntegratorOptions opt;
    opt.rtol = opt.atol = 1e3;  // never rejects: every step is h
    opt.max_step = opt.initial_step = h[k];
    OscRun run = RunOscillator(10.0, 10.0, opt);
    ASSERT_TRUE(run.result.ok) << run.result.cause;
    EXPECT_EQ(run.result.stats.steps, std::lround(10.0 / h[k]));
    EXPECT_EQ(run.result.stats.err_test_fails, 0);
    err[k] = run.end_err;
  }
  const double order = std::log2(err[0] / err[1]);
  std::printf("[ dop853 ] fixed step: error %.3e (h 0.2), %.3e (h 0.1): observed order %.2f\n", err[0], err[1], order);
  constexpr double kOrderTolerance = 0.6;  // pre-asymptotic and odd-order terms
  EXPECT_NEAR(order, 8.0, kOrderTolerance);
}

// Adaptive: the global error follows the tolerance (error / rtol bounded over six decades)
// and the step count grows like rtol^(-1/8) (order 8: a thousand times tighter costs
// 1000^(1/8) = 2.4 times the steps; order 5 would cost 4).
TEST(SimDop853, AdaptiveErrorFollowsToleranceWithEighthOrderStepGrowth) {
  const double rtols[] = {1e-5, 1e-8, 1e-11};
  long steps[3];
  for (int k = 0; k < 3; ++k) {
    IntegratorOptions opt;
    opt.rtol = opt.atol = rtols[k];
    OscRun run = RunOscillator(10.0, 0.1, opt);
    ASSERT_TRUE(run.result.ok) << run.result.cause;
    steps[k] = run.result.stats.steps;
    std::printf("[ dop853 ] rtol %.0e: %ld steps, %ld rejected, max error %.2e (%.1f rtol)\n", rtols[k], steps[k],
                run.result.stats.err_test_fails, run.max_err, run.max_err / rtols[k]);
    constexpr double kErrorPerRtol = 100;  // ~5 periods; local error per step <= rtol
    EXPECT_LT(run.max_err, kErrorPerRtol * rtols[k]);
  }
  for (int k = 0; k + 1 < 3; ++k) {
    const double growth = static_cast<double>(steps[k + 1]) / static_cast<double>(steps[k]);
    EXPECT_GT(growth, 1.8) << "steps should grow with the tolerance";
    EXPECT_LT(growth, 3.2) << "more than 1000^(1/8) ~ 2.4: the order is below 8";
  }
}

// y' = -lambda y for three rates: y = exp(-lambda t); the relative error stays within a
// few rtol (a decaying solution forgets earlier local errors).
TEST(SimDop853, ExponentialDecayMatchesClosedForm) {
  const double lambda[3] = {0.5, 1.0, 3.0};
  LambdaOde ode(3, [&lambda](double, const double* y, double* yd) {
    for (int i = 0; i < 3; ++i) yd[i] = -lambda[i] * y[i];
    return 0;
  });
  const double y0[3] = {1.0, 1.0, 1.0};
  IntegratorOptions opt;
  opt.method = rt::Integrator::Dop853;
  opt.rtol = 1e-9;
  opt.atol = 1e-14;
  double worst = 0.0;
  RowCallback cb = [&](double t, const double* y, std::string*) {
    for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(y[i] / std::exp(-lambda[i] * t) - 1.0));
    return 0;
  };
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 5.0, 0.05}, opt, cb);
  ASSERT_TRUE(r.ok) << r.cause;
  std::printf("[ dop853 ] decay: %ld steps, largest relative error %.2e\n", r.stats.steps, worst);
  constexpr double kRelErrorPerRtol = 20;
  EXPECT_LT(worst, kRelErrorPerRtol * opt.rtol);
}

// 10000 output rows over the same steps: the dense output is 7th order, so its error at
// the rows stays within a small factor of the error at the step points (a cubic Hermite
// interpolant on these ~0.1-long steps would be off by ~1e-6). Output instants do not
// change the steps (NORMAL mode), and each step that holds one costs 3 more f, not 3 per
// instant.
TEST(SimDop853, DenseOutputAtTenThousandRowsIsAsAccurateAsTheSteps) {
  IntegratorOptions opt;
  opt.rtol = opt.atol = 1e-10;
  OscRun coarse = RunOscillator(10.0, 10.0, opt);  // rows at 0 and 10 (a step point) only
  OscRun dense = RunOscillator(10.0, 1e-3, opt);
  ASSERT_TRUE(coarse.result.ok && dense.result.ok);
  ASSERT_EQ(dense.rows, 10001);
  const IntegratorStats& c = coarse.result.stats;
  const IntegratorStats& d = dense.result.stats;
  EXPECT_EQ(d.steps, c.steps);
  EXPECT_EQ(d.err_test_fails, c.err_test_fails);
  EXPECT_EQ(d.rhs_evals, c.rhs_evals + 3 * d.steps) << "every step holds rows: 3 extra f each";
  std::printf("[ dop853 ] %ld steps; error at t = 10: %.2e; largest over 10001 rows: %.2e\n", d.steps,
              coarse.end_err, dense.max_err);
  constexpr double kDenseFactor = 3;  // the rows' error is the steps' error, not the interpolant's
  EXPECT_LT(dense.max_err, kDenseFactor * coarse.end_err);
}

// Evaluations of f: 1 at t0 and 1 for the initial-step estimate, then 12 per accepted
// step (the 13th stage is the next step's first), 11 per rejected one, and 3 per step
// that holds an output instant before its end.
TEST(SimDop853, TwelveEvaluationsPerStepPlusThreeForADenseOutput) {
  IntegratorOptions opt;
  opt.rtol = opt.atol = 1e-8;
  OscRun end_only = RunOscillator(10.0, 10.0, opt);
  ASSERT_TRUE(end_only.result.ok);
  const IntegratorStats& s = end_only.result.stats;
  EXPECT_EQ(s.rhs_evals, 2 + 12 * s.steps + 11 * s.err_test_fails);

  opt.initial_step = 0.05;  // no estimate: one evaluation less
  OscRun given = RunOscillator(10.0, 10.0, opt);
  const IntegratorStats& g = given.result.stats;
  EXPECT_EQ(g.rhs_evals, 1 + 12 * g.steps + 11 * g.err_test_fails);

  // One row in the middle of a step: 3 more evaluations, once.
  opt.initial_step = 0.0;
  OscRun one_row = RunOscillator(10.0, 9.99, opt);  // rows at 0, 9.99, 10
  const IntegratorStats& o = one_row.result.stats;
  EXPECT_EQ(o.steps, s.steps);
  EXPECT_EQ(o.rhs_evals, s.rhs_evals + 3);
  EXPECT_LT(one_row.max_err, 100 * opt.rtol);
}

// The stop time is never stepped past (f is never asked beyond it), the last row is
// exactly `stop` although the interval does not divide the span, and max_step holds.
TEST(SimDop853, NeverStepsPastStopAndHonoursMaxStep) {
  LambdaOde ode = Oscillator();
  const double y0[2] = {1.0, 0.0};
  IntegratorOptions opt;
  opt.method = rt::Integrator::Dop853;
  opt.rtol = opt.atol = 1e-6;
  std::vector<double> times;
  RowCallback cb = [&](double t, const double*, std::string*) {
    times.push_back(t);
    return 0;
  };
  const double stop = 1.2345678;
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, stop, 0.3}, opt, cb);
  ASSERT_TRUE(r.ok) << r.cause;
  EXPECT_EQ(times.back(), stop);
  EXPECT_LE(ode.max_t, stop);

  opt.max_step = 0.01;
  LambdaOde bounded = Oscillator();
  r = Integrate(bounded, y0, OutputGrid{0.0, 1.0, 0.5}, opt, cb);
  ASSERT_TRUE(r.ok) << r.cause;
  EXPECT_GE(r.stats.steps, 100);
  EXPECT_LE(r.stats.last_step, 0.01);
}

// Too many steps between two output instants: a failure that says so.
TEST(SimDop853, MaxStepsBetweenRowsIsAFailure) {
  IntegratorOptions opt;
  opt.rtol = opt.atol = 1e-10;
  opt.max_steps = 5;
  OscRun run = RunOscillator(10.0, 10.0, opt);
  EXPECT_FALSE(run.result.ok);
  EXPECT_NE(run.result.cause.find("too much work"), std::string::npos) << run.result.cause;
}

// f < 0 (fatal) past t = 0.5: the run fails at that evaluation (a stage of the step that
// crosses 0.5, so anywhere in it), with f's cause, and f is not called again.
TEST(SimDop853, FatalRhsFailureStopsAtItsTime) {
  LambdaOde ode(1, [](double t, const double*, double* yd) {
    yd[0] = 1.0;
    return t > 0.5 ? -1 : 0;
  });
  const double y0[1] = {0.0};
  IntegratorOptions opt;
  opt.method = rt::Integrator::Dop853;
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 1.0, 0.01}, opt, [](double, const double*, std::string*) {
    return 0;
  });
  EXPECT_FALSE(r.ok);
  EXPECT_GT(r.fail_time, 0.5);
  EXPECT_EQ(r.fail_time, ode.max_t) << "the failing evaluation is the last one";
  EXPECT_EQ(r.cause, "test failure cause");
}

// f > 0 (recoverable) once, at the first call past t = 0.5: the step is retried shorter
// and the run ends as accurate as an undisturbed one.
TEST(SimDop853, RecoverableRhsFailureShrinksTheStepAndGoesOn) {
  bool failed_once = false;
  LambdaOde ode(2, [&failed_once](double t, const double* y, double* yd) {
    if (t > 0.5 && !failed_once) {
      failed_once = true;
      return 1;
    }
    yd[0] = y[1];
    yd[1] = -kW * kW * y[0];
    return 0;
  });
  const double y0[2] = {1.0, 0.0};
  IntegratorOptions opt;
  opt.method = rt::Integrator::Dop853;
  opt.rtol = opt.atol = 1e-9;
  double err = 0.0;
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 3.0, 0.1}, opt, [&](double t, const double* y, std::string*) {
    err = std::max(err, OscillatorError(t, y));
    return 0;
  });
  ASSERT_TRUE(r.ok) << r.cause;
  EXPECT_TRUE(failed_once);
  EXPECT_LT(err, 100 * opt.rtol);
}

// f > 0 (recoverable) for every t > 0.5: the steps shrink onto 0.5 until they underflow;
// the run fails just past 0.5 with f's cause (not a bare "step size underflow").
TEST(SimDop853, PersistentRecoverableFailureEndsTheRunNearItsTime) {
  LambdaOde ode(1, [](double t, const double*, double* yd) {
    yd[0] = 1.0;
    return t > 0.5 ? 1 : 0;
  });
  const double y0[1] = {0.0};
  IntegratorOptions opt;
  opt.method = rt::Integrator::Dop853;
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 1.0, 0.25}, opt, [](double, const double*, std::string*) {
    return 0;
  });
  EXPECT_FALSE(r.ok);
  EXPECT_GT(r.fail_time, 0.5);
  EXPECT_LT(r.fail_time, 0.5 + 1e-3);
  EXPECT_EQ(r.cause, "test failure cause");
}

// A jump of 1e12 in f at t = 0.5 cannot be resolved at atol 1e-10 (the local error of a
// step across it is about h 1e12): the step shrinks to nothing and the cause says so.
TEST(SimDop853, UnresolvableJumpIsAStepSizeUnderflow) {
  LambdaOde ode(1, [](double t, const double*, double* yd) {
    yd[0] = t < 0.5 ? 0.0 : 1e12;
    return 0;
  });
  const double y0[1] = {0.0};
  IntegratorOptions opt;
  opt.method = rt::Integrator::Dop853;
  opt.rtol = opt.atol = 1e-10;
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 1.0, 0.25}, opt, [](double, const double*, std::string*) {
    return 0;
  });
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.cause.find("step size underflow"), std::string::npos) << r.cause;
  EXPECT_NEAR(r.fail_time, 0.5, 1e-9);
}

// The double pendulum (examples/double_pendulum.mech) through rt::Compile and Simulate:
// over 10 s (chaotic, many swings) the total energy, from the engine's own energy
// signals, stays within a small multiple of rtol of its start, relative to the largest
// kinetic energy; and q(2 s) agrees with CVODE at rtol 1e-12 (an independent method)
// within a multiple of rtol.
TEST(SimDop853, DoublePendulumKeepsEnergyAndMatchesCvode) {
  auto model = test::LoadModel(test::kRoot + "/examples/double_pendulum.mech");
  ASSERT_TRUE(model && model->prog);
  const rt::Program& p = *model->prog;
  constexpr double kRtol = 1e-8;
  sim::MemorySink s = test::RunModel(p, 10.0, 0.01, kRtol, {"shoulder.q", "elbow.q", "kinetic_energy",
                                                             "potential_energy"},
                                     rt::Integrator::Dop853);
  ASSERT_EQ(s.times.size(), 1001u);
  const double e0 = s.rows[0][2] + s.rows[0][3];
  double drift = 0.0, ke_max = 0.0;
  for (const auto& row : s.rows) {
    drift = std::max(drift, std::abs(row[2] + row[3] - e0));
    ke_max = std::max(ke_max, row[2]);
  }
  std::printf("[ dop853 ] double pendulum 10 s, rtol %.0e: energy drift %.2e of max KE %.2f (= %.1f rtol)\n", kRtol,
              drift, ke_max, drift / ke_max / kRtol);
  constexpr double kDriftPerRtol = 20;
  EXPECT_LT(drift / ke_max, kDriftPerRtol * kRtol);

  sim::MemorySink a = test::RunModel(p, 2.0, 0.5, kRtol, {"shoulder.q", "elbow.q"}, rt::Integrator::Dop853);
  sim::MemorySink b = test::RunModel(p, 2.0, 0.5, 1e-12, {"shoulder.q", "elbow.q"}, rt::Integrator::CvodeAdams);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  double diff = 0.0;
  for (size_t k = 0; k < a.rows.size(); ++k)
    for (size_t i = 0; i < 2; ++i) diff = std::max(diff, std::abs(a.rows[k][i] - b.rows[k][i]));
  std::printf("[ dop853 ] double pendulum q over 2 s: DOP853 at %.0e vs CVODE at 1e-12: %.2e\n", kRtol, diff);
  constexpr double kAgreementPerRtol = 100;  // 2 s of a chaotic system: a few swings
  EXPECT_LT(diff, kAgreementPerRtol * kRtol);
}

// An event function g = y = t (t - a)(t - b) (y' = 3t^2 - 2(a + b) t + ab, y(0) = 0, exact for
// DOP853, so one first step of 1 spans it) from zero at the start: it rises, falls through
// zero at t = a and rises again by the step's end, with its graze guard -y' negative at both
// ends. The signs at the step's ends show nothing; the crossing at a is the event. (A sliding
// joint's s u from its reversal's restart did this in a friction chain, issue 41: its stop was
// missed.) If this fails, a function that starts a step at zero is only searched where it ends
// the step below zero.
TEST(SimDop853, AFunctionFromZeroThatFallsThroughZeroInsideTheStepIsAnEvent) {
  constexpr double a = 0.2, b = 0.5;
  class Cubic final : public OdeSystem {
   public:
    int Size() const override { return 1; }
    int Rhs(double t, const double*, double* yd) override {
      yd[0] = 3.0 * t * t - 2.0 * (a + b) * t + a * b;
      return 0;
    }
    std::string FailureCause() const override { return "test failure cause"; }
    int NumEvents() const override { return 2; }
    int EventFunctions(double t, const double* y, double* g) override {
      double yd = 0.0;
      Rhs(t, y, &yd);
      g[0] = y[0];
      g[1] = -yd;  // the graze guard of g[0]
      return 0;
    }
    int Paired(int i) const override { return i == 1 ? 0 : -1; }
    int Event(double t, double*, int i) override {
      events.emplace_back(t, i);
      return 0;
    }
    std::vector<std::pair<double, int>> events;
  } ode;
  IntegratorOptions opt;
  opt.method = rt::Integrator::Dop853;
  opt.rtol = opt.atol = 1e-10;
  opt.initial_step = 1.0;
  const double y0[1] = {0.0};
  const IntegrateResult r =
      Integrate(ode, y0, OutputGrid{0.0, 1.0, 1.0}, opt, [](double, const double*, std::string*) { return 0; });
  EXPECT_TRUE(r.ok) << r.cause;
  ASSERT_FALSE(ode.events.empty()) << "the crossing at t = a was not seen";
  EXPECT_EQ(ode.events.front().second, 0);
  EXPECT_NEAR(ode.events.front().first, a, 1e-12);
}

}  // namespace
}  // namespace kanesim::sim
