// DOP853's stiffness detection (sim/dop853_stiffness.h) and the automatic choice's hand-over
// to CVODE-BDF (sim/integrator.cpp, docs/integrators.md "The automatic choice"). Before it,
// DOP853 crept through a stiff problem at its stability limit: hundreds of thousands of
// evaluations of f, or "too much work". Checked against CVODE-BDF run on its own (an
// independent method), the closed form where there is one, and the rows' bookkeeping
// (every instant once, in order).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "sim/integrator.h"
#include "tests/sim/lambda_ode.h"
#include "tests/support/load_util.h"

namespace kanesim::sim {
namespace {

// y' = -L (y - cos t) - sin t: y = cos t, with a fast mode of rate L (Hairer & Wanner II's
// model of a stiff problem whose solution is smooth).
constexpr double kL = 1e5;
LambdaOde StiffCosine() {
  return LambdaOde(1, [](double t, const double* y, double* yd) {
    yd[0] = -kL * (y[0] - std::cos(t)) - std::sin(t);
    return 0;
  });
}

struct CosRun {
  IntegrateResult result;
  std::vector<double> t, y;
};

CosRun RunCosine(rt::Integrator method, bool switch_when_stiff) {
  LambdaOde ode = StiffCosine();
  IntegratorOptions opt;
  opt.method = method;
  opt.rtol = opt.atol = 1e-8;
  opt.switch_when_stiff = switch_when_stiff;
  CosRun run;
  RowCallback cb = [&run](double t, const double* y, std::string*) {
    run.t.push_back(t);
    run.y.push_back(y[0]);
    return 0;
  };
  const double y0 = 1.0;
  run.result = Integrate(ode, &y0, OutputGrid{0.0, 2.0, 0.05}, opt, cb);
  return run;
}

double MaxError(const CosRun& r) {
  double e = 0.0;
  for (size_t k = 0; k < r.t.size(); ++k) e = std::max(e, std::abs(r.y[k] - std::cos(r.t[k])));
  return e;
}

TEST(SimStiffnessSwitch, StiffLinearProblemSwitchesEarlyAndKeepsEveryRowOnce) {
  const CosRun plain = RunCosine(rt::Integrator::Dop853, false);
  const CosRun sw = RunCosine(rt::Integrator::Dop853, true);
  ASSERT_TRUE(plain.result.ok) << plain.result.cause;
  ASSERT_TRUE(sw.result.ok) << sw.result.cause;
  // Explicitly chosen: detected (noted), never switched.
  EXPECT_FALSE(std::isnan(plain.result.stats.stiff_time));
  EXPECT_FALSE(plain.result.stats.switched);
  EXPECT_TRUE(sw.result.stats.switched);
  EXPECT_GT(sw.result.stats.stiff_h_lambda, 6.1);
  std::printf("[ stiff ] y' = -1e5 (y - cos t): DOP853 %ld f, switched at t = %.3g after %ld f\n",
              plain.result.stats.rhs_evals, sw.result.stats.stiff_time,
              sw.result.stats.rhs_evals + sw.result.stats.rhs_evals_jac);
  EXPECT_LT(sw.result.stats.rhs_evals + sw.result.stats.rhs_evals_jac, 0.05 * plain.result.stats.rhs_evals);
  // Every instant once, in order, on the closed form.
  ASSERT_EQ(sw.t.size(), 41u);
  for (size_t k = 0; k < sw.t.size(); ++k) EXPECT_DOUBLE_EQ(sw.t[k], 0.05 * static_cast<double>(k)) << k;
  EXPECT_LT(MaxError(sw), 1e-6);
}

TEST(SimStiffnessSwitch, NonStiffOscillatorIsNeverFoundStiff) {
  LambdaOde ode(2, [](double, const double* y, double* yd) {
    yd[0] = y[1];
    yd[1] = -4.0 * y[0];
    return 0;
  });
  IntegratorOptions opt;
  opt.method = rt::Integrator::Dop853;
  opt.rtol = opt.atol = 1e-3;  // loose: long steps, the ones that visit the stability boundary
  opt.switch_when_stiff = true;
  const double y0[2] = {1.0, 0.0};
  RowCallback cb = [](double, const double*, std::string*) { return 0; };
  IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 50.0, 1.0}, opt, cb);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(std::isnan(r.stats.stiff_time));
  EXPECT_FALSE(r.stats.switched);
}

// The model: a light link held by stiff joint friction. Auto (which picks DOP853 here: no
// spring or damper element) hands over to CVODE-BDF early, spends a small fraction of
// DOP853's evaluations, and its rows match CVODE-BDF chosen explicitly.
SimResult RunFriction(const rt::Program& p, rt::Integrator method, double tol, MemorySink* sink) {
  SimOptions o;
  o.stop_time = 1.0;
  o.interval = 0.01;
  o.rtol = o.atol = tol;
  o.integrator = method;
  o.signals = {"hinge.q", "hinge.u"};
  return Simulate(p, o, *sink);
}

TEST(SimStiffnessSwitch, StiffFrictionUnderAutoHandsOverToCvodeBdf) {
  auto model = test::LoadModel(test::kRoot + "/tests/sim/models/stiff_friction.mech");
  ASSERT_TRUE(model && model->prog);
  const rt::Program& p = *model->prog;
  constexpr double kTol = 1e-8;
  MemorySink dop, aut, bdf;
  const SimResult rd = RunFriction(p, rt::Integrator::Dop853, kTol, &dop);
  const SimResult ra = RunFriction(p, rt::Integrator::Auto, kTol, &aut);
  const SimResult rb = RunFriction(p, rt::Integrator::CvodeBdf, kTol, &bdf);
  ASSERT_EQ(ra.status, SimResult::Status::kOk) << ra.message;
  ASSERT_EQ(rb.status, SimResult::Status::kOk) << rb.message;
  EXPECT_EQ(ra.stats.method, rt::Integrator::Dop853) << "the model must be one auto gives DOP853";
  const IntegratorStats& a = ra.stats.integrator;
  EXPECT_TRUE(a.switched);
  const long dop_f = rd.stats.integrator.rhs_evals;
  std::printf("[ stiff ] friction 1 s: DOP853 %ld f (status %d); auto %ld f, switched at t = %.3g (h|lambda| %.3g)\n",
              dop_f, static_cast<int>(rd.status), a.rhs_evals + a.rhs_evals_jac, a.stiff_time, a.stiff_h_lambda);
  EXPECT_LT(a.rhs_evals + a.rhs_evals_jac, 0.05 * static_cast<double>(dop_f));
  ASSERT_EQ(aut.times.size(), 101u);
  ASSERT_EQ(bdf.times.size(), 101u);
  double diff = 0.0;
  for (size_t k = 0; k < aut.times.size(); ++k) {
    EXPECT_EQ(aut.times[k], bdf.times[k]) << k;
    diff = std::max(diff, std::abs(aut.rows[k][0] - bdf.rows[k][0]));
  }
  std::printf("[ stiff ] friction q: auto vs CVODE-BDF at %.0e: %.2e\n", kTol, diff);
  EXPECT_LT(diff, 1e3 * kTol);
}

}  // namespace
}  // namespace kanesim::sim
