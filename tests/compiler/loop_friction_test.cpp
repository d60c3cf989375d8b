// Exact Coulomb stick-slip beside constraint rows (issue 41; docs/stdlib.md "Revolute"): a
// stuck joint is one more row, held by the friction force the constrained system needs (its
// response through the rows' reactions, the constrained inverse mass). Checked against the
// static torque by virtual work on the four-bar of examples/fourbar.mech, and against the
// reduced one-degree-of-freedom model of a geared pair with the friction reflected through
// the ratio, in all five integrators.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kA = 0.2, kB = 0.6, kC = 0.5;         // examples/fourbar.mech: crank, coupler, rocker
constexpr double kMa = 0.5, kMb = 1.0, kMc = 0.8, kG = 9.81;  // their masses (uniform rods), gravity -y

// examples/fourbar.mech at rest (omega0 = 0) with `crank_mods` on the crank's joint and
// `rocker_mods` on the rocker's.
std::string FourBarAtRest(const std::string& crank_mods, const std::string& rocker_mods = "") {
  FourBarText bar;
  bar.omega0 = 0;
  bar.crank_mods = crank_mods;
  bar.rocker_mods = rocker_mods;
  return bar.Text();
}

// dV/d(theta2): the torque that holds the crank at rest against gravity through the loop, by
// virtual work. V = g (m_a a/2 sin t2 + m_b (a sin t2 + b/2 sin t3) + m_c c/2 sin t4), with
// dt3, dt4 per dt2 from the loop's velocity equations a e^{i t2} + b w3 e^{i t3} = c w4 e^{i t4}.
double HoldingTorque(double t2, double t3, double t4) {
  // b w3 cos t3 - c w4 cos t4 = -a cos t2, b w3 sin t3 - c w4 sin t4 = -a sin t2 (Cramer).
  const double det = -kB * std::cos(t3) * kC * std::sin(t4) + kC * std::cos(t4) * kB * std::sin(t3);
  const double w3 = (kA * std::cos(t2) * kC * std::sin(t4) - kC * std::cos(t4) * kA * std::sin(t2)) / det;
  const double w4 = (-kB * std::cos(t3) * kA * std::sin(t2) + kA * std::cos(t2) * kB * std::sin(t3)) / det;
  return kG * (kMa * kA / 2 * std::cos(t2) + kMb * (kA * std::cos(t2) + kB / 2 * std::cos(t3) * w3) +
               kMc * kC / 2 * std::cos(t4) * w4);
}

const std::vector<std::string> kSignals = {"crank_pivot.q",   "crank_pivot.u",  "crank_coupler.q",
                                           "crank_coupler.u", "rocker_pivot.q", "rocker_pivot.u"};

// The holding torque at the state of the last row at time t (an event's right limit).
double HoldingTorqueAt(const sim::MemorySink& s, double t) {
  size_t i = s.times.size();
  while (i-- > 0 && s.times[i] != t) {
  }
  EXPECT_LT(i, s.times.size()) << "no row at t = " << t;
  const std::vector<double>& y = s.rows.at(i);
  return HoldingTorque(y[0], y[0] + y[2], y[4]);
}

// The friction force an event's text reports: "sticks (friction X within B)" or "... (friction
// needed X, at most B)".
double LoggedFriction(const std::string& kind) {
  for (const char* key : {"(friction needed ", "(friction "}) {
    const size_t at = kind.find(key);
    if (at != std::string::npos) return std::strtod(kind.c_str() + at + std::strlen(key), nullptr);
  }
  ADD_FAILURE() << "no friction in '" << kind << "'";
  return NAN;
}

// If this fails, a crank with exact friction in a closed loop was refused (K312, before this
// change), or the friction that holds it at rest is not the static torque gravity needs
// through the loop (virtual work), or the loop crept while stuck.
TEST(LoopFriction, FourBarCrankSticksWithTheTorqueByVirtualWork) {
  auto l = LoadModel(FourBarAtRest(", friction_torque = 2, friction_exact = true"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.0, 0.1, kSignals, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_EQ(r.stats.events.size(), 1u) << how.name;
    const std::vector<double>& y0 = s.rows.front();
    EXPECT_NEAR(y0[0], 0.3, 1e-14);
    const double tau = HoldingTorque(y0[0], y0[0] + y0[2], y0[4]);
    EXPECT_NEAR(tau, 1.4109147004724838, 1e-12);  // the same formula, once by hand (Python)
    EXPECT_EQ(r.stats.events[0].kind.rfind("sticks", 0), 0u) << r.stats.events[0].kind;
    EXPECT_NEAR(LoggedFriction(r.stats.events[0].kind), tau, 1e-9 * tau) << how.name;
    for (const std::vector<double>& y : s.rows) {
      for (int k : {0, 2, 4}) EXPECT_NEAR(y[static_cast<size_t>(k)], y0[static_cast<size_t>(k)], 1e-12) << how.name;
      for (int k : {1, 3, 5}) EXPECT_LE(std::abs(y[static_cast<size_t>(k)]), 1e-12) << how.name;
    }
  }
}

// With the bound 0.5 below the 1.41 gravity needs, the crank slips at once; it swings, each
// stop of the loop deciding: the friction each decision needs is the static torque at the
// state of that moment (the whole loop at rest), it reverses where that exceeds 0.5 and
// sticks for good where it does not, at a time all five integrators agree on. If this fails,
// the stick test does not read the reaction through the loop, or the slip events differ
// between the integrators.
TEST(LoopFriction, FourBarCrankSlipsAboveItsBoundAndSticksWhereGravityNeedsLess) {
  const double bound = 0.5;
  auto l = LoadModel(FourBarAtRest(", friction_torque = " + Num(bound) + ", friction_exact = true"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  double t_stick_ref = NAN;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 2.5, 0.1, kSignals, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<sim::EventRecord>& ev = r.stats.events;
    ASSERT_EQ(ev.size(), 5u) << how.name;  // slip, three reversals, stick
    EXPECT_EQ(ev[0].kind.rfind("slips, backwards", 0), 0u) << ev[0].kind;
    for (size_t k = 0; k < ev.size(); ++k) {
      const double tau = k == 0 ? HoldingTorque(s.rows[0][0], s.rows[0][0] + s.rows[0][2], s.rows[0][4])
                                : HoldingTorqueAt(s, ev[k].time);
      EXPECT_NEAR(LoggedFriction(ev[k].kind), tau, 1e-8 * std::max(1.0, std::abs(tau))) << how.name << " " << ev[k].kind;
      const bool sticks = ev[k].kind.rfind("sticks", 0) == 0;
      EXPECT_EQ(sticks, std::abs(tau) <= bound) << how.name << " " << ev[k].kind;
      EXPECT_EQ(sticks, k + 1 == ev.size()) << how.name << " " << ev[k].kind;
    }
    if (std::isnan(t_stick_ref)) t_stick_ref = ev.back().time;
    EXPECT_NEAR(ev.back().time, t_stick_ref, 1e-8) << how.name;
    const std::vector<double>& y = s.rows.back();
    for (int k : {1, 3, 5}) EXPECT_LE(std::abs(y[static_cast<size_t>(k)]), 1e-12) << how.name;
  }
}

// The rocker's rate per unit crank rate (w4 of HoldingTorque) at crank, coupler, rocker angles.
double RockerRate(double t2, double t3, double t4) {
  const double det = -kB * std::cos(t3) * kC * std::sin(t4) + kC * std::cos(t4) * kB * std::sin(t3);
  return (-kB * std::cos(t3) * kA * std::sin(t2) + kA * std::cos(t2) * kB * std::sin(t3)) / det;
}

// Crank (0.5) and rocker (friction F) both with exact friction at rest: the loop makes their
// motions dependent (one degree of freedom, u_rocker = w4 u_crank), so they are held as one
// (sim/stick_slip.cpp (4)): the torque gravity needs at the crank by virtual work against
// 0.5 + |w4| F, sticking for F = 3 (bound 2.2 > 1.41) and slipping for F = 0.3 (0.80),
// each joint logging the torque and bound reflected onto itself. If this fails, two stuck
// joints whose motions the loop makes dependent stop the run (exit 2: before this change) or
// are held by forces other than the loop's virtual work and their combined bound.
TEST(LoopFriction, DependentStuckJointsAreHeldAsOneWithinTheirCombinedBound) {
  for (double F : {3.0, 0.3}) {
    auto l = LoadModel(FourBarAtRest(", friction_torque = 0.5, friction_exact = true",
                                     ", friction_torque = " + Num(F) + ", friction_exact = true"),
                       {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, F > 1.0 ? 1.0 : 0.2, 0.1, kSignals, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      const std::vector<double>& y0 = s.rows.front();
      const double tau = HoldingTorque(y0[0], y0[0] + y0[2], y0[4]), w4 = RockerRate(y0[0], y0[0] + y0[2], y0[4]);
      const double bound = 0.5 + std::abs(w4) * F;
      ASSERT_GE(r.stats.events.size(), 2u) << how.name;
      const sim::EventRecord &crank = r.stats.events[0], &rocker = r.stats.events[1];
      EXPECT_EQ(crank.time, 0.0);
      EXPECT_EQ(rocker.time, 0.0);
      EXPECT_EQ(crank.element, "crank_pivot");
      EXPECT_EQ(rocker.element, "rocker_pivot");
      const char* law = tau <= bound ? "sticks" : "slips";
      EXPECT_EQ(crank.kind.rfind(law, 0), 0u) << how.name << ": " << crank.kind;
      EXPECT_EQ(rocker.kind.rfind(law, 0), 0u) << how.name << ": " << rocker.kind;
      EXPECT_NE(crank.kind.find("held as one with 'rocker_pivot'"), std::string::npos) << crank.kind;
      EXPECT_NEAR(LoggedFriction(crank.kind), tau, 1e-9 * tau) << how.name;
      EXPECT_NEAR(LoggedFriction(rocker.kind), tau / w4, 1e-9 * std::abs(tau / w4)) << how.name;
      EXPECT_NE(crank.kind.find(Num(bound).substr(0, 12)), std::string::npos) << bound << " " << crank.kind;
      if (tau <= bound) {
        ASSERT_EQ(r.stats.events.size(), 2u) << how.name;
        for (const std::vector<double>& y : s.rows) {
          for (int k : {0, 2, 4}) EXPECT_EQ(y[static_cast<size_t>(k)], y0[static_cast<size_t>(k)]) << how.name;
          for (int k : {1, 3, 5}) EXPECT_EQ(y[static_cast<size_t>(k)], 0.0) << how.name;
        }
      } else {
        EXPECT_LT(s.rows.back()[0], y0[0]) << how.name;  // the crank falls back
      }
    }
  }
}

// A gear pair (JointCoupling, q2 = -q1 / 2) in the horizontal plane (gravity along the axes:
// no work), driven by a torque on j1, with exact friction only on j2 (0.4). The reduced
// model: one joint carrying rod 1 and a rod with rod 2's inertia times the ratio squared, its
// friction 0.4 times |ratio| = 0.2, the same drive. If this fails, the stuck j2's force is not
// the one the coupled system needs, or its slip and stick differ from the reduced model's.
TEST(LoopFriction, GearedPairEqualsTheReducedModelWithReflectedFriction) {
  const std::string drive = "  j1.tau = 0.3 * sin(time);\n";
  const std::string geared =
      GearedPair("Geared", "{0, 0, -9.81}", "", ", friction_torque = 0.4, friction_exact = true", drive);
  const std::string reduced =
      "model Reduced\n"
      "  World world(g = {0, 0, -9.81});\n"
      "  Revolute j1(axis = {0, 0, 1}, friction_torque = 0.2, friction_exact = true);\n"
      "  Rod r1(L = 1, m = 1);\n"
      "  Rod r2(L = 0.5, m = 0.5);\n"
      "equation\n"
      "  connect(world.frame_b, j1.frame_a);\n"
      "  connect(j1.frame_b, r1.frame_a);\n"
      "  connect(j1.frame_b, r2.frame_a);\n" +
      drive + "end Reduced;\n";
  auto a = LoadModel(geared, {}, {}, true);
  auto b = LoadModel(reduced, {}, {}, true);
  ASSERT_TRUE(a && a->prog) << (a ? Messages(a->errors) : "");
  ASSERT_TRUE(b && b->prog) << (b ? Messages(b->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult ra, rb;
    sim::MemorySink sa = RunWith(*a->prog, how, 10.0, 0.05, {"j1.q", "j1.u", "j2.q"}, &ra, 1e-11);
    sim::MemorySink sb = RunWith(*b->prog, how, 10.0, 0.05, {"j1.q", "j1.u"}, &rb, 1e-11);
    ASSERT_EQ(ra.status, sim::SimResult::Status::kOk) << how.name << ": " << ra.message;
    ASSERT_EQ(rb.status, sim::SimResult::Status::kOk) << how.name << ": " << rb.message;
    ASSERT_EQ(rb.stats.events.size(), 7u) << how.name;
    ASSERT_EQ(ra.stats.events.size(), rb.stats.events.size()) << how.name;
    int sticks = 0;
    for (size_t k = 0; k < ra.stats.events.size(); ++k) {
      const std::string& ka = ra.stats.events[k].kind;
      const std::string& kb = rb.stats.events[k].kind;
      EXPECT_NEAR(ra.stats.events[k].time, rb.stats.events[k].time, 1e-8) << how.name << ": " << ka << " / " << kb;
      EXPECT_EQ(ka.substr(0, ka.find(' ')), kb.substr(0, kb.find(' '))) << how.name;  // (j2 slides the other way)
      // j2's force times the ratio is j1's (virtual work: tau2 dq2 = tau2 (-1/2) dq1).
      const bool stuck = ka.rfind("sticks", 0) == 0;
      sticks += stuck ? 1 : 0;
      if (ka.find("friction") != std::string::npos) {
        EXPECT_NEAR(-0.5 * LoggedFriction(ka), LoggedFriction(kb), 1e-8) << how.name << ": " << ka << " / " << kb;
      }
    }
    EXPECT_EQ(sticks, 4) << how.name;  // at 0, 3.32, 6.46, 9.61
    ASSERT_EQ(sa.rows.size(), sb.rows.size()) << how.name;
    // ARKODE's explicit stages at rtol 1e-11 leave 1.1e-7 over the 10 s; the others 2e-8.
    const double tol = how.kind == rt::Integrator::ArkodeErk ? 3e-7 : 5e-8;
    for (size_t i = 0; i < sa.rows.size(); ++i) {
      EXPECT_NEAR(sa.rows[i][0], sb.rows[i][0], tol) << how.name << " t = " << sa.times[i];
      EXPECT_NEAR(sa.rows[i][1], sb.rows[i][1], tol) << how.name << " t = " << sa.times[i];
      EXPECT_NEAR(sa.rows[i][2], -0.5 * sa.rows[i][0], 1e-12) << how.name;
    }
  }
}

}  // namespace
}  // namespace kanesim::test
