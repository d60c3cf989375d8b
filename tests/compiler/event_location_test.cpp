// Locating events inside one step (issue 41; docs/integrators.md "End stops"): DOP853 locates
// only the earliest crossing of an accepted step on its dense output, the others in the steps
// after the event (docs/benchmarks/2026-11-29_root_finding.md). Two sliders on horizontal
// prismatic joints (no force along them) reach their stops at closed-form times close enough
// to share one step; the first is also a spring oscillator whose stop is a graze (its gap
// dips below zero and is back above it within one step), before a crossing of the other.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

// Slider a at speed -1 from 0 onto q_min = -ta; slider b likewise onto -tb; restitution 1/2.
// With k > 0, a is a spring oscillator instead (a.q = cos t from 1 at rest, q_min given as
// -ta: a graze near t = pi when ta is close to 1).
std::string Sliders(double ta, double tb, double k = 0.0) {
  const std::string a_start = k > 0.0 ? "q(start = 1), u(start = 0)" : "q(start = 0), u(start = -1)";
  return "model Sliders\n"
         "  World world(g = {0, -9.81, 0});\n"
         "  Prismatic a(axis = {1, 0, 0}, " + a_start + ", q_min = " + Num(-ta) + ", restitution = 0.5);\n"
         "  Body ma(m = 1);\n"
         "  Prismatic b(axis = {0, 0, 1}, q(start = 0), u(start = -1), q_min = " + Num(-tb) + ", restitution = 0.5);\n"
         "  Body mb(m = 1);\n"
         "equation\n"
         "  connect(world.frame_b, a.frame_a);\n"
         "  connect(a.frame_b, ma.frame_a);\n"
         "  connect(world.frame_b, b.frame_a);\n"
         "  connect(b.frame_b, mb.frame_a);\n"
         "  a.tau = " + Num(-k) + " * a.q;\n"
         "end Sliders;\n";
}

// Two stops reached 1e-3 s apart (in one step: the motion is linear, the steps long), in
// either order of the event functions. Each impact at its closed-form time d / v, the second
// after the first's restart: the earliest is the event, the later one is not lost.
TEST(EventLocation, TheEarliestOfTwoCrossingsInOneStepComesFirstAndTheOtherFollows) {
  for (const auto& [ta, tb] : {std::pair{0.3, 0.301}, std::pair{0.301, 0.3}}) {
    auto l = LoadModel(Sliders(ta, tb), {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 0.5, 0.5, {"a.q", "b.q"}, &r);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      const std::vector<double> a = EventTimes(r, "a", "impact"), b = EventTimes(r, "b", "impact");
      ASSERT_EQ(a.size(), 1u) << how.name << "\n" << EventLog(r);
      ASSERT_EQ(b.size(), 1u) << how.name << "\n" << EventLog(r);
      EXPECT_NEAR(a[0], ta, 1e-12) << how.name;
      EXPECT_NEAR(b[0], tb, 1e-12) << how.name;
      ASSERT_EQ(r.stats.events.size(), 2u) << how.name << "\n" << EventLog(r);
      EXPECT_EQ(r.stats.events[0].element, ta < tb ? "a" : "b") << how.name << "\n" << EventLog(r);
      // The end: each back from its stop at half its speed since its impact.
      EXPECT_NEAR(s.rows.back()[0], -ta + 0.5 * (0.5 - ta), 1e-10) << how.name;
      EXPECT_NEAR(s.rows.back()[1], -tb + 0.5 * (0.5 - tb), 1e-10) << how.name;
    }
  }
}

// Slider a oscillates, a.q = cos t, onto q_min = -(1 - d): its gap dips below zero at
// ta = pi - acos(1 - d) and would be back above it at pi + acos(1 - d), a window of 0.028 s
// that one step covers; slider b reaches its stop at tb = pi - 0.005, inside that window,
// where a is still below its stop. a's impact at ta is the event (b's crossing after it).
// DOP853 at three output grids: its steps do not depend on where the rows are, nor do its
// event times (the SUNDIALS integrators' steps end on output instants: their times move
// with the grid within their error, the crossing's slope 0.014 magnifying it).
// If this fails with b's event first (and then 'an impact was missed' or a row below a's
// stop), a step located only the crossings before the earliest one of the functions that end
// it below zero, and a's dip (back above zero by the step's end, its graze guard's minimum
// after tb) was skipped (fix/rootfind before this test).
TEST(EventLocation, AGrazeBeforeAnotherCrossingInTheSameStepIsTheEvent) {
  const double d = 1e-4, ta = M_PI - std::acos(1.0 - d), tb = M_PI - 0.005;
  auto l = LoadModel(Sliders(1.0 - d, tb, 1.0), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    const bool dop853 = how.kind == rt::Integrator::Dop853;
    std::vector<double> first;  // DOP853: the event times of the first grid
    for (double interval : {3.5, 0.1, 0.013}) {
      for (double tol : {1e-8, 1e-10}) {
        sim::SimResult r;
        sim::MemorySink s = RunWith(*l->prog, how, 3.5, interval, {"a.q", "b.q"}, &r, tol);
        const std::string what = std::string(how.name) + " interval " + Num(interval) + " tol " + Num(tol);
        ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << what << ": " << r.message << "\n" << EventLog(r);
        ASSERT_GE(r.stats.events.size(), 2u) << what << "\n" << EventLog(r);
        EXPECT_EQ(r.stats.events[0].element, "a") << what << "\n" << EventLog(r);
        const std::vector<double> a = EventTimes(r, "a", "impact"), b = EventTimes(r, "b", "impact");
        ASSERT_GE(a.size(), 1u) << what << "\n" << EventLog(r);
        ASSERT_EQ(b.size(), 1u) << what << "\n" << EventLog(r);
        // q's error over the crossing speed sin(ta) = 0.014: DOP853's ~tol, the others' more
        // (CVODE at 1e-8: 2.6e-5 s), still well inside the 0.009 s between ta and tb.
        EXPECT_NEAR(a[0], ta, (dop853 ? 2e3 : 1e5) * tol) << what;
        EXPECT_NEAR(b[0], tb, 1e-9) << what;
        for (size_t i = 0; i < s.rows.size(); ++i) {
          ASSERT_GE(s.rows[i][0], -(1.0 - d) - 1e-7) << what << " t = " << s.times[i];
          ASSERT_GE(s.rows[i][1], -tb - 1e-9) << what << " t = " << s.times[i];
        }
        if (!dop853 || tol != 1e-10) continue;
        if (first.empty()) {
          first = {a[0], b[0]};
        } else {
          EXPECT_NEAR(a[0], first[0], 1e-12) << what << ": another grid moved the event";
          EXPECT_NEAR(b[0], first[1], 1e-12) << what << ": another grid moved the event";
        }
      }
    }
  }
}

}  // namespace
}  // namespace kanesim::test
