// The stiff hand-over (sim/dop853_stiffness.h, docs/integrators.md "The automatic choice") in
// the stepping core (sim/simulator.h: Python's model.simulator(), the FMU's doStep). If these
// fail, a stiff model stepped under the automatic choice crawls through DOP853 where `run`
// switches to CVODE-BDF, its stiffness is not reported, or reset() does not start over.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "sim/simulator.h"
#include "tests/support/load_util.h"

namespace kanesim::sim {
namespace {

// The model of SimStiffnessSwitch: a light link held by stiff joint friction (auto: DOP853).
constexpr double kTol = 1e-8;
constexpr double kDt = 0.01;  // the caller's step: 100 of them to t = 1

std::shared_ptr<const rt::Program> StiffFriction() {
  auto model = test::LoadModel(test::kRoot + "/tests/sim/models/stiff_friction.mech");
  return model ? model->prog : nullptr;
}

std::unique_ptr<Simulator> MakeStepping(const std::shared_ptr<const rt::Program>& p, rt::Integrator m) {
  SimulatorOptions o;
  o.integrator = m;
  o.rtol = o.atol = kTol;
  o.signals = {"hinge.q", "hinge.u"};
  std::string error;
  auto s = Simulator::Make(p, o, &error);
  EXPECT_TRUE(s) << error;
  return s;
}

// hinge.q after each of the 100 steps (empty when a step failed).
std::vector<double> StepToOne(Simulator& s) {
  std::vector<double> q;
  double out[2];
  std::string error;
  for (int k = 1; k <= 100; ++k) {
    const StepResult r = s.AdvanceTo(kDt * k);
    EXPECT_TRUE(r.ok) << "t = " << r.fail_time << ": " << r.cause;
    if (!r.ok || !s.Outputs(out, &error)) return {};
    q.push_back(out[0]);
  }
  return q;
}

// Stepped under auto: handed over as `run` does, a small fraction of DOP853's evaluations, and
// every step's q equal to the rows of `run` (auto, itself checked against CVODE-BDF) to the
// tolerance's reach. reset() starts over with DOP853 and switches again at the same instant.
TEST(SimulatorStiffness, AutoHandsOverToCvodeBdfAsRunDoes) {
  auto p = StiffFriction();
  ASSERT_TRUE(p);
  const MemorySink run = test::RunModel(*p, 1.0, kDt, kTol, {"hinge.q", "hinge.u"});
  ASSERT_EQ(run.times.size(), 101u);

  auto dop = MakeStepping(p, rt::Integrator::Dop853);
  auto aut = MakeStepping(p, rt::Integrator::Auto);
  ASSERT_TRUE(dop && aut);
  EXPECT_EQ(aut->Method(), rt::Integrator::Dop853) << "the model must be one auto gives DOP853";
  ASSERT_EQ(StepToOne(*dop).size(), 100u);
  const std::vector<double> q = StepToOne(*aut);
  ASSERT_EQ(q.size(), 100u);

  const IntegratorStats a = aut->Stats(), d = dop->Stats();
  EXPECT_TRUE(a.switched);
  EXPECT_FALSE(d.switched);  // an explicit DOP853 only notes it
  EXPECT_FALSE(std::isnan(d.stiff_time));
  EXPECT_GT(a.stiff_h_lambda, 6.1);
  EXPECT_EQ(aut->Method(), rt::Integrator::CvodeBdf);
  const long fa = a.rhs_evals + a.rhs_evals_jac;
  std::printf("[ stiff ] stepped 100 x 0.01: DOP853 %ld f; auto %ld f, switched at t = %.3g\n", d.rhs_evals, fa,
              a.stiff_time);
  EXPECT_LT(fa, 0.1 * static_cast<double>(d.rhs_evals));
  double diff = 0.0;
  for (size_t k = 0; k < q.size(); ++k) diff = std::max(diff, std::abs(q[k] - run.rows[k + 1][0]));
  std::printf("[ stiff ] stepped auto vs run auto, q at 1e-08: %.2e\n", diff);
  EXPECT_LT(diff, 1e3 * kTol);

  const double first = a.stiff_time;
  aut->Reset();
  EXPECT_EQ(aut->Method(), rt::Integrator::Dop853);
  EXPECT_FALSE(aut->Stats().switched);
  ASSERT_EQ(StepToOne(*aut), q);  // the same path again, bit for bit
  EXPECT_EQ(aut->Stats().stiff_time, first);
}

}  // namespace
}  // namespace kanesim::sim
