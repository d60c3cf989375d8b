// Two joints with exact friction whose speeds the constraint rows tie together (a geared
// pair, both joints with friction), stuck together (issue 41; sim/stick_slip.cpp (4)): their
// stuck rows and the coupling's are dependent, the forces that hold them not unique, only
// their power: with u2 = k u1, T = tau1 + k tau2 holds the pair, within B1 + |k| B2. So the
// pair is one joint with the reflected inertia I1 + k^2 I2 and the reflected friction
// B1 + |k| B2: checked against that one-joint model, from rest, after a reinit stops the pair
// and with mu N friction on an accelerating carrier, in all five integrators.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

constexpr double kRatio = -0.5;  // GearedPair's and GearOnCarrier's coupling: u2 = -u1 / 2

// The friction an event's text reports: "sticks (friction X within B...)" or "... (friction
// needed X, at most B...)"; B after `at most` / `within`.
double Logged(const std::string& kind, bool bound) {
  const char* keys[2][2] = {{"(friction needed ", "(friction "}, {", at most ", " within "}};
  for (const char* key : keys[bound ? 1 : 0]) {
    const size_t at = kind.find(key);
    if (at != std::string::npos) return std::strtod(kind.c_str() + at + std::strlen(key), nullptr);
  }
  ADD_FAILURE() << "no friction in '" << kind << "'";
  return NAN;
}

std::string FirstWord(const std::string& s) { return s.substr(0, s.find(' ')); }

// The events of element `who`, or of every element but the joint `not_who`.
std::vector<sim::EventRecord> EventsOf(const sim::SimResult& r, const std::string& who, bool but = false) {
  std::vector<sim::EventRecord> out;
  for (const sim::EventRecord& e : r.stats.events)
    if ((e.element == who) != but) out.push_back(e);
  return out;
}

// The geared pair (j2's friction reflected, B1 + |k| B2) against the one-joint model: the same
// events of j1 (times to 1e-8, the friction and bound each logs equal to the one joint's), j2's
// events beside j1's at the same times (j2 sliding the other way, its friction -1/k times
// j1's), j1's motion the one joint's and j2's speed exactly zero while the pair is stuck; j1's
// slips from rest at the closed-form times `slips` (where the drive reaches the bound), to 1e-9.
void ExpectOneJoint(const std::string& pair, const std::string& one, double stop, size_t sticks,
                    const std::vector<double>& slips, double row_tol) {
  auto a = LoadModel(pair, {}, {}, true);
  auto b = LoadModel(one, {}, {}, true);
  ASSERT_TRUE(a && a->prog) << (a ? Messages(a->errors) : "");
  ASSERT_TRUE(b && b->prog) << (b ? Messages(b->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult ra, rb;
    sim::MemorySink sa = RunWith(*a->prog, how, stop, 0.05, {"j1.q", "j1.u", "j2.q", "j2.u"}, &ra, 1e-11);
    sim::MemorySink sb = RunWith(*b->prog, how, stop, 0.05, {"j1.q", "j1.u"}, &rb, 1e-11);
    ASSERT_EQ(ra.status, sim::SimResult::Status::kOk) << how.name << ": " << ra.message;
    ASSERT_EQ(rb.status, sim::SimResult::Status::kOk) << how.name << ": " << rb.message;
    const std::vector<sim::EventRecord> ea = EventsOf(ra, "j2", true), eb = rb.stats.events, e2 = EventsOf(ra, "j2");
    ASSERT_EQ(ea.size(), eb.size()) << how.name;
    ASSERT_EQ(e2.size(), EventsOf(ra, "j1").size()) << how.name;
    size_t stuck = 0, k2 = 0, slipped = 0;
    for (size_t k = 0; k < ea.size(); ++k) {
      const std::string& ka = ea[k].kind;
      const std::string& kb = eb[k].kind;
      EXPECT_NEAR(ea[k].time, eb[k].time, 1e-8) << how.name << ": " << ka << " / " << kb;
      EXPECT_EQ(FirstWord(ka), FirstWord(kb)) << how.name << ": " << ka << " / " << kb;
      if (ea[k].element != "j1") continue;
      stuck += FirstWord(ka) == "sticks" ? 1 : 0;
      if (FirstWord(ka) == "slips," && slipped < slips.size()) {
        EXPECT_NEAR(ea[k].time, slips[slipped++], 1e-9) << how.name << ": " << ka;
      }
      for (bool bound : {false, true})
        EXPECT_NEAR(Logged(ka, bound), Logged(kb, bound), 1e-8) << how.name << ": " << ka << " / " << kb;
      const sim::EventRecord& j2 = e2.at(k2++);  // j2 decides with j1, its numbers reflected through 1/k
      EXPECT_EQ(j2.time, ea[k].time) << how.name << ": " << j2.kind;
      EXPECT_EQ(FirstWord(j2.kind), FirstWord(ka)) << how.name << ": " << j2.kind;
      EXPECT_NEAR(Logged(j2.kind, false), Logged(ka, false) / kRatio, 1e-12) << how.name << ": " << j2.kind;
      EXPECT_NEAR(Logged(j2.kind, true), Logged(ka, true) / std::abs(kRatio), 1e-12) << how.name << ": " << j2.kind;
    }
    EXPECT_EQ(stuck, sticks) << how.name;
    EXPECT_EQ(slipped, slips.size()) << how.name;
    ASSERT_EQ(sa.rows.size(), sb.rows.size()) << how.name;
    for (size_t i = 0; i < sa.rows.size(); ++i) {
      EXPECT_NEAR(sa.rows[i][0], sb.rows[i][0], row_tol) << how.name << " t = " << sa.times[i];
      EXPECT_NEAR(sa.rows[i][1], sb.rows[i][1], row_tol) << how.name << " t = " << sa.times[i];
      EXPECT_NEAR(sa.rows[i][2], kRatio * sa.rows[i][0], 1e-12) << how.name;
      if (sb.rows[i][1] == 0.0) {
        EXPECT_EQ(sa.rows[i][3], 0.0) << how.name << " t = " << sa.times[i];  // held exactly
      }
    }
  }
}

// The one-joint model of GearedPair: rod 1 (I1 = 1/3) and a rod of rod 2's inertia times
// k^2 (m = 2 / 4: I = 1/24), friction torque `friction` (B1 + |k| B2).
std::string OneJoint(double friction, const std::string& equations, double u0 = 0.0) {
  return "model One\n  World world(g = {0, 0, -9.81});\n  Revolute j1(axis = {0, 0, 1}, u(start = " + Num(u0) +
         "), friction_torque = " + Num(friction) +
         ", friction_exact = true);\n  Rod r1(L = 1, m = 1);\n  Rod r2(L = 0.5, m = 0.5);\nequation\n"
         "  connect(world.frame_b, j1.frame_a);\n  connect(j1.frame_b, r1.frame_a);\n"
         "  connect(j1.frame_b, r2.frame_a);\n" +
         equations + "end One;\n";
}

// Both joints with constant exact friction (0.05 on j1, 0.3 on j2: 0.05 + 0.3 / 2 = 0.2 on the
// one joint), gravity along the axes, a drive 0.3 sin t on j1: from rest the pair sticks
// together, slips where the drive passes 0.2, and sticks again where it stops while the drive
// is below 0.2. If this fails, two stuck joints tied by a coupling stop the run (exit 2, "the
// constraints make their motions dependent": before this change), or the pair is not held by
// the friction of both joints reflected through the ratio.
TEST(CoupledStick, GearedPairWithFrictionOnBothJointsIsOneJointWithTheReflectedFriction) {
  const std::string drive = "  j1.tau = 0.3 * sin(time);\n";
  const std::string pair =
      GearedPair("Pair", "{0, 0, -9.81}", ", friction_torque = 0.05, friction_exact = true",
                 ", friction_torque = 0.3, friction_exact = true", drive);
  // (ARKODE's explicit stages at rtol 1e-11 leave 1.1e-7 over the 10 s; the others 2e-8.)
  const double s = std::asin(0.2 / 0.3);  // 0.3 sin t = +-0.2
  ExpectOneJoint(pair, OneJoint(0.2, drive), 10.0, 4, {s, M_PI + s, 2 * M_PI + s}, 3e-7);
}

// The pair (friction 0.15 on j1, 0.1 on j2: 0.15 + 0.1 / 2 = 0.2 again) slides from the start
// (u1 = 2) until a reinit stops it (j1.u to 0; j2 follows through the coupling) at t = 2.9,
// where the drive 0.3 sin 2.9 = 0.072 is below the pair's 0.2: both joints are stuck right
// after the jump, held as one until the drive passes -0.2 (t = pi + asin(2/3)). If this
// fails, the pair stuck after a velocity jump stops the run (exit 2 at the reinit, "the
// constraints make their motions dependent": before this change), or it slips at another
// time than the one joint.
TEST(CoupledStick, PairStoppedByAReinitSticksAsOneJoint) {
  const std::string eqs = "  j1.tau = 0.3 * sin(time);\n  when time > 2.9 then\n    reinit(j1.u, 0);\n  end when;\n";
  const std::string pair =
      GearedPair("Pair", "{0, 0, -9.81}", ", u(start = 2), friction_torque = 0.15, friction_exact = true",
                 ", friction_torque = 0.1, friction_exact = true", eqs);
  ExpectOneJoint(pair, OneJoint(0.2, eqs, 2.0), 5.0, 1, {M_PI + std::asin(0.2 / 0.3)}, 1e-7);
}

// (Before this change the sliding start below was a silent wrong answer: after the jump j1
// stuck alone, j2 kept its sliding friction at zero speed, and the pair slipped at 2.93.)
// A carrier on an x rail, pushed by a constant force F (acceleration a = F / (m_c + m1 + m2)),
// carries a gear pair of discs centred on their axes, both with exact friction mu (pin
// radii r1, r2): each disc's joint carries m_i a across its axis, N_i = m_i a whatever the
// discs turn, so the pair's bound is mu1 r1 m1 a + |k| mu2 r2 m2 a: the one joint's with
// mu r1 m1 = mu1 r1 m1 + |k| mu2 r2 m2 carrying I1 + k^2 I2, disc 2's mass on the carrier.
// The drive on j1 and a reinit of j1's speed to 0 (the friction impulse law: j2 slides with
// its speed 0 after, by the coupling) as in the constant-friction tests.
constexpr double kMc = 1.5, kM1 = 2.0, kM2 = 3.0, kI1 = 0.3, kI2 = 0.8, kMu1 = 0.4, kMu2 = 0.6, kR1 = 0.05,
                 kR2 = 0.08, kF = 13.0;

std::string GearOnCarrier(bool one, const std::string& equations, double u0) {
  const double mu_one = (kMu1 * kR1 * kM1 + std::abs(kRatio) * kMu2 * kR2 * kM2) / (kR1 * kM1);
  auto disc = [](const std::string& name, double m, double i) {
    return "  Body " + name + "(m = " + Num(m) + ", I = diagonal({" + Num(i) + ", " + Num(i) + ", " + Num(i) + "}));\n";
  };
  auto joint = [](const std::string& name, double mu, double r, double u) {
    return "  Revolute " + name + "(axis = {0, 0, 1}, u(start = " + Num(u) + "), mu = " + Num(mu) +
           ", friction_radius = " + Num(r) + ", friction_exact = true);\n";
  };
  std::string t = "model G\n  World world(g = {0, 0, 0});\n  Prismatic rail(axis = {1, 0, 0});\n  Body carrier(m = " +
                  Num(kMc) + ");\n";
  if (one) {
    t += joint("j1", mu_one, kR1, u0) + disc("d1", kM1, kI1 + kRatio * kRatio * kI2) + disc("d2", kM2, 0.0) +
         "equation\n  connect(carrier.frame_a, d2.frame_a);\n";
  } else {
    t += joint("j1", kMu1, kR1, u0) + disc("d1", kM1, kI1) + "  FixedTranslation base(r = {2, 0, 0});\n" +
         joint("j2", kMu2, kR2, kRatio * u0) + disc("d2", kM2, kI2) + "  JointCoupling gear(ratio = " + Num(kRatio) +
         ");\nequation\n  connect(carrier.frame_a, base.frame_a);\n  connect(base.frame_b, j2.frame_a);\n"
         "  connect(j2.frame_b, d2.frame_a);\n  connect(j1.drive, gear.flange_a);\n  connect(j2.drive, gear.flange_b);\n";
  }
  return t + "  connect(world.frame_b, rail.frame_a);\n  connect(rail.frame_b, carrier.frame_a);\n"
             "  connect(carrier.frame_a, j1.frame_a);\n  connect(j1.frame_b, d1.frame_a);\n  rail.tau = " +
         Num(kF) + ";\n" + equations + "end G;\n";
}

// The pair's bound is 0.4 0.05 2 a + 0.5 0.6 0.08 3 a = 0.112 a (a = 2 m/s^2: 0.224). From
// rest the drive 0.3 sin t passes it at asin(0.224 / 0.3) = 0.843; sliding from the start
// (u1 = 2) and stuck by the reinit at 2.9, at pi + 0.843. If this fails, the pair's mu N bound is not the sum
// of the joints' reflected (B1 + |k| B2, N of each joint), or the pair stuck after the
// jump's friction impulses stops the run (exit 2: before this change).
TEST(CoupledStick, GearOnACarrierWithMuNIsOneJointWithTheReflectedFriction) {
  const std::string eqs = "  j1.tau = 0.3 * sin(time);\n  when time > 2.9 then\n    reinit(j1.u, 0);\n  end when;\n";
  const double bound = (kMu1 * kR1 * kM1 + std::abs(kRatio) * kMu2 * kR2 * kM2) * kF / (kMc + kM1 + kM2);
  ASSERT_NEAR(bound, 0.224, 1e-15);
  const double s = std::asin(bound / 0.3);
  ExpectOneJoint(GearOnCarrier(false, eqs, 0.0), GearOnCarrier(true, eqs, 0.0), 5.0, 2, {s, M_PI + s}, 1e-7);
  ExpectOneJoint(GearOnCarrier(false, eqs, 2.0), GearOnCarrier(true, eqs, 2.0), 5.0, 1, {M_PI + s}, 1e-7);
}

}  // namespace
}  // namespace kanesim::test
