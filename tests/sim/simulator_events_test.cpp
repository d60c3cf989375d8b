// The stepping core with events (sim/simulator.h over sim/hybrid_ode.h), in all five
// integrators: a when clause's reinit located inside the steps at the bouncing ball's closed
// form, its terminate ending the step there; exact friction's stick; states saved before an
// event and in a mode (a follower held by a resting stop too) continuing bit for bit. If
// these fail, stepping integrates through the events, ends a step at the wrong time or loses
// a mode in GetState / SetState.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "sim/simulator.h"
#include "tests/support/load_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::sim {
namespace {

constexpr char kWhenBall[] = R"(model WhenBall
  parameter Real e = 0.8;
  World world(g = {0, -9.81, 0});
  Prismatic p(axis = {0, 1, 0}, q(start = 1));
  Body b(m = 1, I = diagonal({1, 1, 1}));
equation
  connect(world.frame_b, p.frame_a);
  connect(p.frame_b, b.frame_a);
  when p.q < 0 then
    reinit(p.u, -e * pre(p.u));
  end when;
  when time > 2 then
    terminate("two seconds");
  end when;
end WhenBall;
)";

constexpr char kSlider[] = R"(model Slider
  World world(g = {0, -9.81, 0});
  Prismatic slide(axis = {1, 0, 0}, q(start = 1), mu = 0.3, mu_s = 0.5, friction_exact = true);
  Body box(m = 1);
equation
  connect(world.frame_b, slide.frame_a);
  connect(slide.frame_b, box.frame_a);
  slide.tau = -10 * slide.q;
end Slider;
)";

// The rack pair (tests/support/model_texts.h, as in tests/compiler/held_signals_test.cpp):
// block 1 rests on its stop until 0.5 and holds block 2 through the gear (held by the stop,
// not by its friction); both stuck by block 2's friction until 1.0886, then sliding.
const std::string kRackOnStop = test::RackPairText{}.Text();

const rt::Integrator kAll[] = {rt::Integrator::Dop853, rt::Integrator::CvodeAdams, rt::Integrator::CvodeBdf,
                               rt::Integrator::IDA, rt::Integrator::ArkodeErk};

std::unique_ptr<Simulator> Make(const std::string& text, rt::Integrator m) {
  auto l = test::LoadModel(text, {}, {}, /*is_text=*/true);
  if (!l || !l->prog) return nullptr;
  SimulatorOptions o;
  o.integrator = m;
  o.rtol = o.atol = 1e-10;
  std::string error;
  auto s = Simulator::Make(l->prog, o, &error);
  EXPECT_TRUE(s) << error;
  return s;
}

// Steps of 0.01 from Time() to `to` (or a terminate); the states after each.
std::vector<std::vector<double>> Steps(Simulator& s, double to) {
  std::vector<std::vector<double>> out;
  const double t0 = s.Time();
  for (int k = 1; k <= static_cast<int>(std::lround((to - t0) / 0.01)); ++k) {
    const StepResult r = s.AdvanceTo(t0 + 0.01 * k);
    EXPECT_TRUE(r.ok) << r.cause;
    out.push_back(s.State());
    if (r.terminated || !r.ok) break;
  }
  return out;
}

TEST(SimulatorEvents, AWhenBallFiresAtTheClosedFormAndTerminatesInsideTheStep) {
  const double t1 = std::sqrt(2.0 / 9.81), e = 0.8;
  for (rt::Integrator m : kAll) {
    auto s = Make(kWhenBall, m);
    ASSERT_TRUE(s);
    Steps(*s, 3.0);
    std::string why;
    ASSERT_TRUE(s->Terminated(&why)) << MethodName(m);
    EXPECT_EQ(why, "two seconds");
    EXPECT_NEAR(s->Time(), 2.0, 1e-12) << MethodName(m);  // not the step's end, 2.0 + round-off
    double want = t1;
    int fires = 0;
    for (const EventRecord& r : s->Events()) {
      if (r.kind != "fires") continue;
      EXPECT_NEAR(r.time, want, 1e-8) << MethodName(m) << " bounce " << fires;
      want += 2.0 * std::pow(e, ++fires) * t1;
    }
    EXPECT_EQ(fires, 3) << MethodName(m);
    const StepResult after = s->Step(0.01);
    EXPECT_FALSE(after.ok);
    EXPECT_NE(after.cause.find("terminated"), std::string::npos) << after.cause;
  }
}

TEST(SimulatorEvents, StatesSavedBeforeAnEventAndInAModeContinueBitForBit) {
  for (rt::Integrator m : kAll) {
    for (const std::string& text : {std::string(kWhenBall), std::string(kSlider), kRackOnStop}) {
      auto s = Make(text, m);
      ASSERT_TRUE(s);
      // Before the first bounce (0.45) / the stick (0.99) / the leave (0.5: the follower held by
      // the stop), and between bounces / stuck / sliding.
      for (double at : {0.4, 1.2}) {
        Steps(*s, at);
        const SimulatorState saved = s->GetState();
        const auto first = Steps(*s, 1.9);
        const size_t events = s->Events().size();
        std::string error;
        ASSERT_TRUE(s->SetState(saved, &error)) << error;
        EXPECT_EQ(Steps(*s, 1.9), first) << MethodName(m) << " from " << at;
        EXPECT_EQ(s->Events().size(), events);
        ASSERT_TRUE(s->SetState(saved, &error));
      }
      // A mode that is not one (a stuck flag of 0.5) is refused, the simulator unchanged.
      SimulatorState bad = s->GetState();
      if (!bad.modes.empty()) {
        bad.modes[0] = 0.5;
        std::string error;
        EXPECT_FALSE(s->SetState(bad, &error));
        EXPECT_NE(error.find("modes"), std::string::npos) << error;
      }
    }
  }
}

TEST(SimulatorEvents, ExactFrictionSticksAtPiOverOmega) {
  // x = c + (1 - c) cos(w t) sliding back (c = mu g m / k, w = sqrt(k / m)); stuck at pi / w.
  const double c = 0.3 * 9.81 / 10, w = std::sqrt(10.0);
  for (rt::Integrator m : kAll) {
    auto s = Make(kSlider, m);
    ASSERT_TRUE(s);
    Steps(*s, 1.5);
    ASSERT_FALSE(s->Events().empty());
    EXPECT_NEAR(s->Events().back().time, M_PI / w, 1e-8) << MethodName(m);
    EXPECT_NEAR(s->State()[0], 2 * c - 1, 1e-8) << MethodName(m);
    EXPECT_EQ(s->State()[1], 0.0) << MethodName(m);
  }
}

// A rod (L = 1, m = 1) resting on its stop q_min = 0.2 under gravity, driven by tau = 10 t:
// the outputs read the held motion (a = 0, the hinge's axial reaction the static torque
// m g (L/2) cos 0.2), then after the leave at t* = m g (L/2) cos 0.2 / 10 the free one,
// a = (10 t - m g (L/2) cos q) / (m L^2 / 3). If this fails, stepping's outputs (Python's
// simulator(), an FMU's) read the free motion on the stop.
TEST(SimulatorEvents, OutputsOnAStopAreTheHeldMotions) {
  const std::string text = test::PendulumText{.mods = ", q(start = 0.2), q_min = 0.2, tau = 10 * time"}.Text();
  const double statics = 9.81 * 0.5 * std::cos(0.2), t_leave = statics / 10;
  for (rt::Integrator m : kAll) {
    auto l = test::LoadModel(text, {}, {}, /*is_text=*/true);
    ASSERT_TRUE(l && l->prog);
    SimulatorOptions o;
    o.integrator = m;
    o.rtol = o.atol = 1e-10;
    o.signals = {"j1.q", "j1.a", "j1.reaction_torque[3]"};
    std::string error;
    auto s = Simulator::Make(l->prog, o, &error);
    ASSERT_TRUE(s) << error;
    for (int k = 1; k <= 7; ++k) {
      const double t = 0.1 * k;
      ASSERT_TRUE(s->AdvanceTo(t).ok) << MethodName(m);
      double v[3];
      ASSERT_TRUE(s->Outputs(v, &error)) << error;
      if (t < t_leave) {
        EXPECT_EQ(v[1], 0.0) << MethodName(m) << " t = " << t;
        EXPECT_NEAR(v[2], statics, 1e-12) << MethodName(m) << " t = " << t;
      } else {
        const double a = (10 * t - statics / std::cos(0.2) * std::cos(v[0])) * 3;
        EXPECT_NEAR(v[1], a, 1e-8 * (1 + std::abs(a))) << MethodName(m) << " t = " << t;
        EXPECT_NEAR(v[2], 10 * t, 1e-9) << MethodName(m) << " t = " << t;
      }
    }
  }
}

}  // namespace
}  // namespace kanesim::sim
