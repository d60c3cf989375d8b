// A held row's release found however long the steps had grown (sim/integrator.h,
// OdeSystem::Holding): while a joint is stuck the state stands still, no error estimate
// limits the step, and DOP853's steps grew six-fold each until one stepped over the whole
// window in which the drive passes the friction bound: the gear below stayed stuck for 4 s
// (a silent wrong answer) where the other integrators slipped at asin(2/3)/3.
// The release bound (sim/release_bound.h): a drive that passes the friction bound only in a
// window much narrower than the output interval or the caller's step, found in every
// integrator, in a run and through the stepping API.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "sim/simulator.h"
#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

// A gear pair in the horizontal plane (gravity along the axes: no work), exact friction 0.2 on
// the driving joint, the drive 0.3 sin(3t): stuck at rest until 0.3 sin(3t) reaches 0.2.
const std::string kGeared = GearedPair("Geared", "{0, 0, -9.81}", ", friction_torque = 0.2, friction_exact = true", "",
                                        "  j1.tau = 0.3 * sin(3 * time);\n");

// If this fails, an integrator stepped over the slip window of a stuck joint (its first event
// after the stick at the start is not the slip at asin(2/3)/3), or the joint moved while stuck.
TEST(HeldStep, AStuckJointSlipsWhenTheDrivePassesItsBoundInEveryIntegrator) {
  auto l = LoadModel(kGeared, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double t_slip = std::asin(2.0 / 3.0) / 3.0;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 4.0, 0.008, {"j1.q", "j1.u"}, &r, 1e-10);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<sim::EventRecord>& ev = r.stats.events;
    ASSERT_GE(ev.size(), 2u) << how.name;
    EXPECT_EQ(ev[0].kind.rfind("sticks", 0), 0u) << how.name << " " << ev[0].kind;
    EXPECT_EQ(ev[1].kind.rfind("slips", 0), 0u) << how.name << " " << ev[1].kind;
    EXPECT_NEAR(ev[1].time, t_slip, 1e-8) << how.name;
    // Still to round-off: the stuck force is Newton's on the coupled pair (sim/stick_slip.cpp),
    // its acceleration zero to kChordTol, so q may be a few ulps of nothing (1e-58 seen).
    for (size_t k = 0; k < s.times.size() && s.times[k] < t_slip; ++k)
      EXPECT_LE(std::abs(s.rows[k][0]), 1e-30) << how.name << " t = " << s.times[k];
  }
}

// The same pair, its drive c t sin(w t) growing through the bound 0.2: the first peak past it
// (at about t = 1.064) passes it by 2 %, a window of about 0.013 s, and the peak before stays 9 %
// below. Stuck from the start; it slips where c t sin(w t) = 0.2 and, sliding against the
// constant friction 0.2, stops where the impulse of the drive minus the friction since the slip
// is zero (the effective inertia cancels):
//   F(t) = c [sin(w s) / w^2 - s cos(w s) / w] from ts to t - 0.2 (t - ts) = 0.
constexpr double kW = 31.0;
const double kPeak = (M_PI / 2 + 10 * M_PI) / kW;
constexpr double kC = 0.191713;  // 0.2 * 1.02 / kPeak
const std::string kPulse = GearedPair("Pulse", "{0, 0, -9.81}", ", friction_torque = 0.2, friction_exact = true", "",
                                      "  j1.tau = 0.191713 * time * sin(31 * time);\n");

double Drive(double t) { return kC * t * std::sin(kW * t); }
double SlipTime() { return Bisect([](double t) { return Drive(t) - 0.2; }, kPeak - 0.02, kPeak); }
double StickTime() {
  const double c = kC, ts = SlipTime();
  auto prim = [&](double s) { return c * (std::sin(kW * s) / (kW * kW) - s * std::cos(kW * s) / kW); };
  return Bisect([&](double t) { return prim(t) - prim(ts) - 0.2 * (t - ts); }, kPeak + 1e-3, kPeak + 0.05);
}

// If this fails, an integrator stepped over a release window narrower than the output interval:
// the joint stayed stuck (no slip near 1.06), or slipped or stuck again at the wrong time.
TEST(HeldStep, ANarrowSlipWindowIsFoundInEveryIntegrator) {
  auto l = LoadModel(kPulse, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double ts = SlipTime(), te = StickTime();
  ASSERT_GT(te - ts, 0.005);  // the window is narrow against the interval 0.1, not degenerate
  ASSERT_LT(te - ts, 0.03);
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    RunWith(*l->prog, how, 1.15, 0.1, {"j1.q"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<sim::EventRecord>& ev = r.stats.events;
    if (ev.size() != 3u) {  // stick, slip, stick
      ADD_FAILURE() << how.name << ": " << ev.size() << " events, the last " << (ev.empty() ? "" : ev.back().kind);
      continue;
    }
    EXPECT_EQ(ev[1].kind.rfind("slips", 0), 0u) << how.name << " " << ev[1].kind;
    EXPECT_NEAR(ev[1].time, ts, 1e-8) << how.name;
    EXPECT_EQ(ev[2].kind.rfind("sticks", 0), 0u) << how.name << " " << ev[2].kind;
    EXPECT_NEAR(ev[2].time, te, 1e-8) << how.name;
  }
}

// If this fails, the stepping API (Python's step, an FMU's doStep) stepped over the window
// inside one caller's step of 0.5 s: no error estimate bounds a step while the joint is stuck.
TEST(HeldStep, ANarrowSlipWindowIsFoundInsideLargeStepsOfTheSimulator) {
  auto l = LoadModel(kPulse, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double ts = SlipTime(), te = StickTime();
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimulatorOptions o;
    o.integrator = how.kind;
    o.rtol = o.atol = 1e-11;
    std::string error;
    std::unique_ptr<sim::Simulator> s = sim::Simulator::Make(l->prog, o, &error);
    ASSERT_TRUE(s) << error;
    for (double t : {0.5, 1.0, 1.15}) {
      const sim::StepResult step = s->AdvanceTo(t);
      ASSERT_TRUE(step.ok) << how.name << ": " << step.cause;
    }
    const std::vector<sim::EventRecord>& ev = s->Events();
    if (ev.size() != 3u) {  // stick, slip, stick
      ADD_FAILURE() << how.name << ": " << ev.size() << " events, the last " << (ev.empty() ? "" : ev.back().kind);
      continue;
    }
    EXPECT_EQ(ev[1].kind.rfind("slips", 0), 0u) << how.name << " " << ev[1].kind;
    EXPECT_NEAR(ev[1].time, ts, 1e-8) << how.name;
    EXPECT_EQ(ev[2].kind.rfind("sticks", 0), 0u) << how.name << " " << ev[2].kind;
    EXPECT_NEAR(ev[2].time, te, 1e-8) << how.name;
  }
}

}  // namespace
}  // namespace kanesim::test
