// Plane contacts beside Coulomb friction mu N in mechanisms with constraint rows (issue 41;
// docs/events.md "Friction beside stops"). PlaneFriction's carriage and leg (a carriage m_c on
// a prismatic joint cx along x with friction mu; on it a revolute leg, a massless rod L and a
// point mass m_l at its tip touching the floor y = -L cos phi) driven through a second path:
// a slider m_2 on its own rail px along x, 2 above, tied to the carriage either
//   - by a closed loop: a cut prismatic joint along y between the slider and the carriage
//     (x_slider = x_carriage, r = 1), or
//   - by a coupling: JointCoupling q_cx = r q_px (r = -1/2; the slider's rail elsewhere).
// The drive F on px reaches cx as F / r and the slider's inertia as m_2 / r^2; the slider's
// weight stays on its own rail (the cut joint carries no force along y; the coupling none
// across). So, with m_e = m_2 / r^2 and F_e = F / r, PlaneFriction's hand statics hold with
// the carriage's inertia m_c + m_e and its weight m_c g:
//   tip:      m_l a = -T sin phi,   0 = T cos phi - m_l g + lambda
//   carriage: N = m_c g + T cos phi = m_c g - m_l a cot phi,   lambda = m_l (g + a cot phi)
//   a = (F_e - s mu m_c g) / D_s,   D_s = m_c + m_e + m_l - s mu m_l cot phi            (1)
// Stuck: a = 0, N = m_c g, the bound mu m_c g. Between a slip at t_a and the next stop the
// speed is the integral of (1), zero where (F_e = F0 sin w t)
//   F0 (cos w t_a - cos w t) / w - s mu m_c g (t - t_a) = 0                               (2)
// Lift-off: lambda = 0 where a = -g tan phi.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"
#include "tests/support/sanitizer_cases.h"

namespace kanesim::test {
namespace {

constexpr double kMc = CarriageLegText::kMc, kMl = CarriageLegText::kMl, kL = CarriageLegText::kL;
constexpr double kPhi = CarriageLegText::kPhi, kMu = CarriageLegText::kMu, kM2 = 0.8, kG = 9.81;
const double kCot = 1.0 / std::tan(kPhi);

constexpr double kMw = 0.6, kIw = 0.009, kRw = 0.3;  // the rolling wheel: mass, inertia, radius

struct Tie {
  std::string name;
  double r;  // q_cx = r q_px (loop, coupling)
  double Me() const { return name == "rolling" ? kMw + kIw / (kRw * kRw) : kM2 / (r * r); }
  // The other speed the tie holds: cx.u = K() times it.
  std::string Other() const { return name == "rolling" ? "spin.u" : "px.u"; }
  double K() const { return name == "rolling" ? -kRw : r; }
};
const std::vector<Tie> kTies = {{"loop", 1.0}, {"coupling", -0.5}, {"rolling", 1.0}};

// The mechanism; cx starts at speed uc0 (px at uc0 / r), the leg at q0 with rate w0; `drive`
// the force on px as a function of time.
std::string Carriage(const Tie& tie, double g, double uc0, double q0, double w0, double e, const std::string& law,
                     const std::string& drive) {
  CarriageLegText text{.model = "C", .g = g, .uc0 = uc0, .q0 = q0, .w0 = w0, .e = e, .law = law};
  if (tie.name == "rolling") {
    text.decls = "  Prismatic wy(axis = {0, 1, 0});\n"
                 "  Revolute spin(axis = {0, 0, 1}, u(start = " + Num(-uc0 / kRw) + "));\n"
                 "  Body wheel(m = " + Num(kMw) + ", I = {{" + Num(kIw) + ", 0, 0}, {0, " + Num(kIw) + ", 0}, {0, 0, " + Num(kIw) + "}});\n"
                 "  RollingDisk roll(radius = " + Num(kRw) + ", axis = {0, 0, 1}, n = {0, 1, 0}, p = {0, " + Num(-kRw) + ", 0});\n";
    text.equations = "  connect(carriage.frame_a, wy.frame_a);\n"
                     "  connect(wy.frame_b, spin.frame_a);\n"
                     "  connect(spin.frame_b, wheel.frame_a);\n"
                     "  connect(spin.frame_b, roll.frame_a);\n"
                     "  cx.tau = " + drive + ";\n";
    return text.Text();
  }
  const bool loop = tie.name == "loop";
  text.decls = "  FixedTranslation base(r = {0, 2, " + std::string(loop ? "0" : "1") + "});\n"
               "  Prismatic px(axis = {1, 0, 0}, u(start = " + Num(uc0 / tie.r) + "));\n"
               "  Body slider(m = " + Num(kM2) + ");\n" +
               (loop ? "  Prismatic link(axis = {0, 1, 0}, cut = true);\n" : "  JointCoupling gear(ratio = " + Num(tie.r) + ");\n");
  text.equations = "  connect(world.frame_b, base.frame_a);\n"
                   "  connect(base.frame_b, px.frame_a);\n"
                   "  connect(px.frame_b, slider.frame_a);\n" +
                   std::string(loop ? "  connect(slider.frame_a, link.frame_a);\n  connect(carriage.frame_a, link.frame_b);\n"
                                    : "  connect(px.drive, gear.flange_a);\n  connect(cx.drive, gear.flange_b);\n") +
                   "  px.tau = " + Num(tie.r) + " * (" + drive + ");\n";
  return text.Text();
}

const std::vector<std::string> kLaws = {", friction_v = 1e-9", ", friction_exact = true"};

// If this fails, plane contacts beside mu with constraint rows are refused (K311, before this
// change), the floor's force is left out of the rail's normal force beside the rows (a bound
// mu (m_c + m_l) g: later slips), the rows' reactions are missing from the resting chord, or
// the slider's weight or inertia reaches cx wrongly through the loop or the coupling.
TEST(PlaneLoopFriction, DrivenCarriageSticksAndSlipsAtTheHandTimes) {
  const double F0 = 8.0, w = 3.0, c = kMu * kMc * kG;
  const double t1 = std::asin(c / F0) / w;  // F_e reaches the bound mu m_c g: slips forwards
  auto bracket = [&](double ta, double s) {
    return [=](double t) { return F0 * (std::cos(w * ta) - std::cos(w * t)) / w - s * c * (t - ta); };  // (2)
  };
  const double t2 = Bisect(bracket(t1, 1.0), t1 + 0.5, t1 + 1.0);  // stops (F_e(t2) within the bound: sticks)
  const double t3 = (M_PI + std::asin(c / F0)) / w;               // F_e reaches -mu m_c g: slips backwards
  const double t4 = Bisect(bracket(t3, -1.0), t3 + 0.5, t3 + 1.0);
  ASSERT_LT(std::abs(F0 * std::sin(w * t2)), c);
  ASSERT_LT(std::abs(F0 * std::sin(w * t4)), c);
  const std::string drive = Num(F0) + " * sin(" + Num(w) + " * time)";
  for (size_t ti = 0; ti < kTies.size(); ++ti) {
    const Tie& tie = kTies[ti];
    auto speed = [&](double t) {  // (1) integrated
      if (t > t1 && t < t2) return bracket(t1, 1.0)(t) / (kMc + tie.Me() + kMl - kMu * kMl * kCot);
      if (t > t3 && t < t4) return bracket(t3, -1.0)(t) / (kMc + tie.Me() + kMl + kMu * kMl * kCot);
      return 0.0;
    };
    auto l = LoadModel(Carriage(tie, kG, 0.0, kPhi + 1e-12, 0.0, 0.0, ", friction_exact = true", drive), {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (size_t hi = 0; hi < AllIntegrators().size(); ++hi) {
      // Under the sanitizers each integrator with one tie (sanitizer_cases.h).
      if (!RunsCase(hi, AllIntegrators().size(), ti, kTies.size())) continue;
      const IntegratorChoice& how = AllIntegrators()[hi];
      const std::string who = std::string(how.name) + " " + tie.name;
      sim::SimResult r;
      const sim::MemorySink s = RunWith(*l->prog, how, 2.3, 0.05, {"cx.u", "leg.q", tie.Other()}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << who << ": " << r.message;
      const std::vector<double> slips = EventTimes(r, "cx", "slips");
      std::vector<double> sticks;  // (after the start's)
      for (double t : EventTimes(r, "cx", "sticks"))
        if (t > 0.1) sticks.push_back(t);
      ASSERT_EQ(slips.size(), 2u) << who << "\n" << EventLog(r);
      ASSERT_EQ(sticks.size(), 2u) << who << "\n" << EventLog(r);
      EXPECT_NEAR(slips[0], t1, 1e-8) << who;
      EXPECT_NEAR(sticks[0], t2, 1e-8) << who;
      EXPECT_NEAR(slips[1], t3, 1e-8) << who;
      EXPECT_NEAR(sticks[1], t4, 1e-8) << who;
      EXPECT_TRUE(EventTimes(r, "foot", "leaves").empty()) << who << "\n" << EventLog(r);
      for (size_t i = 0; i < s.times.size(); ++i) {
        // (the start 1e-12 above the floor: a tiny landing impact at ~1e-6 s)
        if (s.times[i] > 1e-3) {
          EXPECT_NEAR(s.rows[i][0], speed(s.times[i]), 1e-8) << who << " t = " << s.times[i];
        }
        EXPECT_NEAR(s.rows[i][1], kPhi, 1e-9) << who << " t = " << s.times[i];
        EXPECT_NEAR(s.rows[i][0], tie.K() * s.rows[i][2], 1e-9) << who << " t = " << s.times[i];  // the tie kept
      }
    }
  }
}

// If this fails, the floor's force is not in the rail's normal force beside the rows (the
// speeds off (1)), or the tip does not leave where that force turns tensile
// (lambda = m_l (g + a cot phi) = 0).
TEST(PlaneLoopFriction, TipLiftsOffWhereTheFloorsForceVanishes) {
  const double k = 40.0, u0 = 5.0, c = kMu * kMc * kG;
  for (size_t ti = 0; ti < kTies.size(); ++ti) {
    const Tie& tie = kTies[ti];
    const double D = kMc + tie.Me() + kMl - kMu * kMl * kCot;
    const double t_lift = (D * kG * std::tan(kPhi) - c) / k;  // (1) with F_e = -k t at a = -g tan phi
    const double u_lift = u0 + (-0.5 * k * t_lift * t_lift - c * t_lift) / D;
    ASSERT_GT(u_lift, 1.0);
    for (const std::string& law : kLaws) {
      auto l = LoadModel(Carriage(tie, kG, u0, kPhi + 1e-12, 0.0, 0.0, law, Num(-k) + " * time"), {}, {}, true);
      ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
      for (size_t hi = 0; hi < AllIntegrators().size(); ++hi) {
        // Under the sanitizers each integrator with one tie, both laws (sanitizer_cases.h).
        if (!RunsCase(hi, AllIntegrators().size(), ti, kTies.size())) continue;
        const IntegratorChoice& how = AllIntegrators()[hi];
        const std::string who = std::string(how.name) + " " + tie.name + law;
        sim::SimResult r;
        const sim::MemorySink s = RunWith(*l->prog, how, t_lift + 0.02, 0.05, {"cx.u"}, &r, 1e-11);
        ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << who << ": " << r.message;
        ASSERT_FALSE(r.stats.events.empty()) << who;
        const double t_r = r.stats.events[0].time, u_r = ChangeOf(r.stats.events[0], "cx.u", true);
        ASSERT_LT(t_r, 1e-4) << who;
        for (size_t i = 0; i < s.times.size(); ++i)
          if (s.times[i] > t_r && s.times[i] <= t_lift) {
            const double t = s.times[i];
            EXPECT_NEAR(s.rows[i][0], u_r + (-0.5 * k * (t * t - t_r * t_r) - c * (t - t_r)) / D, 1e-8) << who << " t = " << t;
          }
        const std::vector<double> leaves = EventTimes(r, "foot", "leaves");
        ASSERT_EQ(leaves.size(), 1u) << who << "\n" << EventLog(r);
        EXPECT_NEAR(leaves[0], t_lift, 1e-8) << who;
        ASSERT_FALSE(EventTimes(r, "foot", "rests").empty()) << who;
        EXPECT_LT(EventTimes(r, "foot", "rests")[0], 1e-4) << who;
      }
    }
  }
}

// Impact (no gravity): the tip's normal speed -> -e times (only the leg's rate moves it:
// dq+ = -e dq-, w = dq+ - dq-); the floor's impulse reaches cx's rail as a normal impulse
// m_l |dv_tip,x| cot phi, and the carriage slides on with the friction impulse -mu of it:
// momentum along x (inertia M = m_c + m_e + m_l) and the rod's impulse give, by hand,
//   P_f = -mu m_l (m_c + m_e) w L cos phi cot phi / (M + mu m_l cot phi)
//   du = (P_f - m_l w L cos phi) / M
// If this fails, the floor's impulse beside the rows is not in the rail's normal impulse (no
// friction impulse), the rows' impulses are (the slider's momentum taken for the rail's), or
// the impact gains energy.
TEST(PlaneLoopFriction, ImpactOfTheTipSlowsTheCarriageByTheFrictionImpulse) {
  for (const Tie& tie : kTies)
    for (double e : {0.0, 0.5, 1.0}) {
      // (the wheel needs its weight on its plane: gravity for it; bounded forces add no impulse)
      const double g = tie.name == "rolling" ? kG : 0.0;
      auto l = LoadModel(Carriage(tie, g, 2.0, 0.68, -2.0, e, ", friction_exact = true", "0"), {}, {}, true);
      ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
      for (const IntegratorChoice& how : AllIntegrators()) {
        const std::string who = std::string(how.name) + " " + tie.name + " e " + Num(e);
        sim::SimResult r;
        const sim::MemorySink s = RunWith(*l->prog, how, 0.1, 0.05, {"kinetic_energy"}, &r, 1e-11);
        ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << who << ": " << r.message;
        ASSERT_FALSE(r.stats.events.empty()) << who;
        const sim::EventRecord& ev = r.stats.events[0];
        ASSERT_EQ(ev.element, "foot") << who << ": " << ev.kind;
        const double u = ChangeOf(ev, "cx.u", false), qd = ChangeOf(ev, "leg.u", false);
        const double wq = -(1.0 + e) * qd, M = kMc + tie.Me() + kMl;
        const double Pf = -kMu * kMl * (kMc + tie.Me()) * wq * kL * std::cos(kPhi) * kCot / (M + kMu * kMl * kCot);
        EXPECT_NEAR(ChangeOf(ev, "leg.u", true), -e * qd, 1e-9) << who;
        EXPECT_NEAR(ChangeOf(ev, "cx.u", true), u + (Pf - kMl * wq * kL * std::cos(kPhi)) / M, 1e-9) << who;
        EXPECT_NEAR(tie.K() * ChangeOf(ev, tie.Other(), true), ChangeOf(ev, "cx.u", true), 1e-9) << who;
        size_t i = 0;  // the event's rows: energy never rises
        while (i + 1 < s.times.size() && s.times[i] != s.times[i + 1]) ++i;
        ASSERT_LT(i + 1, s.times.size()) << who;
        EXPECT_LE(s.rows[i + 1][0], s.rows[i][0]) << who;
      }
    }
}

// examples/fourbar.mech with exact friction mu on its crank's and rocker's pivots and either
// a wall for the rocker's tip (a PlaneContact, e = 0) or the equivalent stop on the rocker
// (q_max = 2.2, e = 0): the tip's x = d + c cos t4 reaches the wall where t4 reaches the stop.
std::string FourBarAgainst(bool wall) {
  std::ifstream in(kRoot + "/examples/fourbar.mech");
  std::stringstream buf;
  buf << in.rdbuf();
  std::string text = buf.str();
  auto put = [&](const std::string& from, const std::string& to) { text.replace(text.find(from), from.size(), to); };
  const std::string law = ", mu = 0.2, friction_exact = true";
  put("q(start = 1.6)", "q(start = 1.6)" + law + (wall ? "" : ", q_max = 2.2, restitution = 0"));
  put("Revolute crank_pivot(axis = {0, 0, 1},", "Revolute crank_pivot(axis = {0, 0, 1}" + law + ",");
  if (wall) {
    put("  Revolute coupler_rocker(axis = {0, 0, 1}, cut = true);\n",
        "  Revolute coupler_rocker(axis = {0, 0, 1}, cut = true);\n  PlaneContact wall(n = {1, 0, 0}, d = " +
            Num(0.6 + 0.5 * std::cos(2.2)) + ");\n");
    put("  connect(rocker.frame_b, coupler_rocker.frame_b);\n",
        "  connect(rocker.frame_b, coupler_rocker.frame_b);\n  connect(rocker.frame_b, wall.frame_a);\n");
  }
  return text;
}

// The four-bar's rocker strikes the wall plastically and the loop rests there, gravity
// pressing it on: the resting wall fixes every joint through the loop, so both pivots' exact
// friction is held by it (no force of their own, which the rows leave undetermined) in the
// run and in its output rows. The impact is where the loop with the stop strikes (the same
// motion before it); after it the loop stays at rest to round-off. If this fails, a joint the
// resting plane holds through the rows is solved as stuck (two dependent stuck rows: the
// run stopped with exit 2, "the resting contacts' reactions ... did not converge", before
// this change), or the held state is lost in the output rows' copy of the modes.
TEST(PlaneLoopFriction, FourBarRestsOnTheWallWithBothPivotsHeldThroughTheLoop) {
  auto a = LoadModel(FourBarAgainst(true), {}, {}, true);
  auto b = LoadModel(FourBarAgainst(false), {}, {}, true);
  ASSERT_TRUE(a && a->prog) << (a ? Messages(a->errors) : "");
  ASSERT_TRUE(b && b->prog) << (b ? Messages(b->errors) : "");
  const std::vector<std::string> sig = {"crank_pivot.u", "rocker_pivot.q", "rocker_pivot.u"};
  for (const IntegratorChoice& how : AllIntegrators()) {
    const std::string who = how.name;
    sim::SimResult ra, rb;
    const sim::MemorySink sa = RunWith(*a->prog, how, 1.5, 0.05, sig, &ra, 1e-11);
    RunWith(*b->prog, how, 1.5, 0.05, sig, &rb, 1e-11);
    ASSERT_EQ(ra.status, sim::SimResult::Status::kOk) << who << ": " << ra.message << "\n" << EventLog(ra);
    ASSERT_EQ(rb.status, sim::SimResult::Status::kOk) << who << ": " << rb.message;
    const std::vector<double> impacts = EventTimes(ra, "wall", "impact"), stops = EventTimes(rb, "rocker_pivot", "impact");
    ASSERT_EQ(impacts.size(), 1u) << who << "\n" << EventLog(ra);
    ASSERT_EQ(stops.size(), 1u) << who << "\n" << EventLog(rb);
    EXPECT_NEAR(impacts[0], stops[0], 1e-9) << who;
    ASSERT_EQ(EventTimes(ra, "wall", "rests").size(), 1u) << who << "\n" << EventLog(ra);
    EXPECT_TRUE(EventTimes(ra, "wall", "leaves").empty()) << who << "\n" << EventLog(ra);
    for (size_t i = 0; i < sa.times.size(); ++i)
      if (sa.times[i] > impacts[0]) {
        EXPECT_LE(std::abs(sa.rows[i][0]), 1e-10) << who << " t = " << sa.times[i];
        EXPECT_NEAR(sa.rows[i][1], 2.2, 1e-9) << who << " t = " << sa.times[i];
        EXPECT_LE(std::abs(sa.rows[i][2]), 1e-10) << who << " t = " << sa.times[i];
      }
  }
}

}  // namespace
}  // namespace kanesim::test
