// reinit of a speed in a closed loop (issue 41, docs/events.md "Statements"): the jump
// M du = A^T mu + e_k lambda with A du = 0 keeps the loop's velocity constraints. A four-bar
// has one degree of freedom, so the other speeds after the jump follow from the loop's
// velocity equations alone (closed form below), and the kinetic energy, quadratic in that
// one speed, scales by (u+ / u-)^2. A speed the loop fixes (the rocker at its extreme, where
// crank and coupler align) cannot be set: exit 2 naming the clause. A rolling sphere's rows
// take the same jump.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

constexpr double kA = 0.2, kB = 0.6, kC = 0.5;  // examples/fourbar.mech: crank, coupler, rocker

// examples/fourbar.mech with `body` (when clauses) before its annotation.
std::string FourBar(const std::string& body) {
  std::ifstream in(kRoot + "/examples/fourbar.mech");
  std::stringstream buf;
  buf << in.rdbuf();
  std::string text = buf.str();
  const size_t at = text.find("  annotation(experiment");
  if (at != std::string::npos) text.insert(at, body);
  return text;
}

// The loop's velocity equations a w2 e^{i t2} + b w3 e^{i t3} = c w4 e^{i t4} (t: absolute
// angles from x), solved for the coupler's and rocker's rates given the crank's w2:
// w3 = -a w2 sin(t2 - t4) / (b sin(t3 - t4)), w4 = a w2 sin(t2 - t3) / (c sin(t4 - t3)).
struct LoopRates {
  double w3, w4;
};
LoopRates FromCrank(double t2, double t3, double t4, double w2) {
  return {-kA * w2 * std::sin(t2 - t4) / (kB * std::sin(t3 - t4)), kA * w2 * std::sin(t2 - t3) / (kC * std::sin(t4 - t3))};
}
// |a w2 e^{i t2} + b w3 e^{i t3} - c w4 e^{i t4}| (m/s): the speeds' constraint residual.
double Residual(double t2, double t3, double t4, double w2, double w3, double w4) {
  const double x = kA * w2 * std::cos(t2) + kB * w3 * std::cos(t3) - kC * w4 * std::cos(t4);
  const double y = kA * w2 * std::sin(t2) + kB * w3 * std::sin(t3) - kC * w4 * std::sin(t4);
  return std::hypot(x, y);
}

const std::vector<std::string> kSignals = {"crank_pivot.q", "crank_pivot.u",  "crank_coupler.q", "crank_coupler.u",
                                           "rocker_pivot.q", "rocker_pivot.u", "kinetic_energy"};

struct Limits {
  std::vector<double> before, after;
  double t = 0.0;
};
// The one event's left- and right-limit rows.
bool OneEvent(const sim::MemorySink& s, Limits* out) {
  int n = 0;
  for (size_t i = 0; i + 1 < s.times.size(); ++i)
    if (s.times[i] == s.times[i + 1]) {
      out->before = s.rows[i];
      out->after = s.rows[i + 1];
      out->t = s.times[i];
      ++n;
    }
  return n == 1;
}

// If this fails, reinit(crank.u, w) in a four-bar was refused (K321, before this change) or
// left the coupler's and rocker's speeds off the loop's velocity equations (stale or not
// following through the rows), or the energy was not that of the new speed.
TEST(WhenLoop, CrankReinitMovesTheLoopByItsVelocityClosedForm) {
  auto l = LoadModel(FourBar("  when time > 0.3 then\n    reinit(crank_pivot.u, 2);\n  end when;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 0.5, 0.1, kSignals, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    Limits e;
    ASSERT_TRUE(OneEvent(s, &e)) << how.name;
    EXPECT_NEAR(e.t, 0.3, 1e-9) << how.name;
    const std::vector<double>& b = e.before;
    const std::vector<double>& a = e.after;
    for (int k : {0, 2, 4}) EXPECT_NEAR(a[k], b[k], 1e-9) << how.name << ": a coordinate moved (beyond the drift)";
    const double u1 = StateSpeed(r, "crank_pivot.u", true), u2 = StateSpeed(r, "crank_coupler.u", true),
                 u3 = StateSpeed(r, "rocker_pivot.u", true);
    EXPECT_EQ(u1, 2.0) << how.name;
    EXPECT_NEAR(a[1], 2.0, 1e-12) << how.name;
    const double t2 = a[0], t3 = a[0] + a[2], t4 = a[4];
    const LoopRates w = FromCrank(t2, t3, t4, 2.0);
    EXPECT_NEAR(u1 + u2, w.w3, 1e-9) << how.name << ": the coupler's absolute rate";
    EXPECT_NEAR(u3, w.w4, 1e-9) << how.name << ": the rocker's rate";
    EXPECT_NEAR(a[5], w.w4, 1e-9) << how.name << ": the rocker's rate (row)";
    const double b1 = StateSpeed(r, "crank_pivot.u", false);
    const double res_before = Residual(t2, t3, t4, b1, b1 + StateSpeed(r, "crank_coupler.u", false),
                                       StateSpeed(r, "rocker_pivot.u", false));
    const double res_after = Residual(t2, t3, t4, u1, u1 + u2, u3);
    EXPECT_LE(res_after, 1e-12) << how.name << " (before: " << res_before << ")";
    EXPECT_NEAR(a[6], b[6] * (2.0 / b[1]) * (2.0 / b[1]), 1e-9 * b[6]) << how.name << ": T+ = T- (u+/u-)^2";
  }
}

// If this fails, reinit of a dependent speed (the rocker's) did not set it, or the crank and
// coupler did not follow by the same velocity equations.
TEST(WhenLoop, RockerReinitSetsTheCrankThroughTheRows) {
  auto l = LoadModel(FourBar("  when time > 0.3 then\n    reinit(rocker_pivot.u, -1.5);\n  end when;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 0.5, 0.1, kSignals, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    Limits e;
    ASSERT_TRUE(OneEvent(s, &e)) << how.name;
    const std::vector<double>& a = e.after;
    EXPECT_EQ(StateSpeed(r, "rocker_pivot.u", true), -1.5) << how.name;
    EXPECT_NEAR(a[5], -1.5, 1e-12) << how.name;
    const double t2 = a[0], t3 = a[0] + a[2], t4 = a[4];
    const LoopRates unit = FromCrank(t2, t3, t4, 1.0);  // rates per unit crank rate
    const double w2 = -1.5 / unit.w4;
    EXPECT_NEAR(a[1], w2, 1e-9 * std::abs(w2)) << how.name;
    EXPECT_NEAR(a[1] + a[3], unit.w3 * w2, 1e-9 * std::abs(w2)) << how.name;
    EXPECT_NEAR(a[6], e.before[6] * (-1.5 / e.before[5]) * (-1.5 / e.before[5]), 1e-8 * e.before[6]) << how.name;
  }
}

// If this fails, a reinit of the rocker's speed at its extreme (rocker_pivot.u crossing
// zero: crank and coupler aligned, the loop fixes the rocker's rate at 0) was run with an
// unbounded impulse instead of stopping (exit 2 through the run's status) naming the clause.
TEST(WhenLoop, ASpeedTheLoopFixesIsRefusedAtTheEvent) {
  auto l = LoadModel(FourBar("  when rocker_pivot.u < 0 then\n    reinit(rocker_pivot.u, 1);\n  end when;\n"), {}, {},
                     true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    RunWith(*l->prog, how, 1.0, 0.1, kSignals, &r, 1e-11);
    EXPECT_EQ(r.status, sim::SimResult::Status::kNumericalFailure) << how.name << ": " << r.message;
    EXPECT_NE(r.message.find("when ("), std::string::npos) << how.name << ": " << r.message;
    EXPECT_NE(r.message.find("fix 'rocker_pivot.u'"), std::string::npos) << how.name << ": " << r.message;
  }
}

// If this fails, a clause setting two speeds of the one-degree-of-freedom four-bar (crank
// and rocker: the loop ties them) ran with some jump instead of stopping, naming the clause.
TEST(WhenLoop, TwoSpeedsTheLoopTiesAreRefusedAtTheEvent) {
  auto l = LoadModel(
      FourBar("  when time > 0.3 then\n    reinit(crank_pivot.u, 2);\n    reinit(rocker_pivot.u, 1);\n  end when;\n"),
      {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  sim::SimResult r;
  RunWith(*l->prog, AllIntegrators()[0], 0.5, 0.1, kSignals, &r, 1e-11);
  EXPECT_EQ(r.status, sim::SimResult::Status::kNumericalFailure) << r.message;
  EXPECT_NE(r.message.find("when ("), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("no unique solution"), std::string::npos) << r.message;
}

// If this fails, reinit of a sphere's speed down an incline (RollingSphere, rows on the
// contact point's velocity) left it off the plane or slipping: after it the centre moves
// along the plane, v_y = v_x tan(alpha), and rolls, w_z = -v_x / (r cos alpha).
TEST(WhenLoop, RollingSphereReinitKeepsItRolling) {
  std::ifstream in(kRoot + "/examples/sphere_incline.mech");
  std::stringstream buf;
  buf << in.rdbuf();
  std::string text = buf.str();
  const size_t at = text.find("  annotation(experiment");
  ASSERT_NE(at, std::string::npos);
  text.insert(at, "  when time > 0.5 then\n    reinit(free.u[1], 0.5);\n  end when;\n");
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double alpha = 0.3, r = 0.1;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult res;
    RunWith(*l->prog, how, 0.7, 0.1, {"free.u[1]"}, &res, 1e-10);
    ASSERT_EQ(res.status, sim::SimResult::Status::kOk) << how.name << ": " << res.message;
    ASSERT_EQ(res.stats.events.size(), 1u) << how.name;
    EXPECT_EQ(StateSpeed(res, "free.u[1]", true), 0.5) << how.name;
    EXPECT_NEAR(StateSpeed(res, "free.u[2]", true), 0.5 * std::tan(alpha), 1e-12) << how.name;
    EXPECT_NEAR(StateSpeed(res, "free.u[6]", true), -0.5 / (r * std::cos(alpha)), 1e-11) << how.name;
  }
}

}  // namespace
}  // namespace kanesim::test
