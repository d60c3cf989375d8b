// Joints stuck by exact friction beside joints resting on their stops (issue 41): the stuck
// joints' forces and the stops' reactions are the multipliers of one constrained system
// (M udot = f + A^T lambda, A udot = b; sim/stick_slip.cpp (2)), solved from one
// factorization of the inverse mass per evaluation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "sim/end_stops.h"
#include "sim/stick_slip.h"
#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;

// A double pendulum in the vertical plane (gravity -y): link 1 (m1 = 1, centre c1 = 0.5 on
// x, length L1 = 1) on joint j1 with friction_torque 100 (it sticks), link 2 (m2 = 0.5,
// centre c2 = 0.4) on joint j2 with a stop q_min = q2, started at rest at (q1, q2). Gravity
// turns j2 towards q_min: it rests there. At rest (u = 0, no velocity terms) the statics give
//   lambda_2 = m2 g c2 cos(q1 + q2)                                  (the stop's reaction)
//   tau_1 = g ((m1 c1 + m2 L1) cos q1 + m2 c2 cos(q1 + q2))          (j1's friction)
// the generalized gravity forces each row balances.
std::string DoublePendulum(double q1, double q2) {
  return ElbowPendulumText{.j1_mods = ", q(start = " + Num(q1) + "), friction_torque = 100, friction_exact = true",
                           .j2_mods = ", q(start = " + Num(q2) + "), q_min = " + Num(q2)}
      .Text();
}

// If this fails, the stuck joint's friction or the stop's reaction is not the statics' (the
// combined rows solve a different system), the held accelerations are not zero, or an
// evaluation with both kinds of rows evaluates the accelerations or factors the inverse mass
// more than once (it evaluated them four times and factored three: Newton on the stuck
// joint's force, the stop's rows held in each of its evaluations), or the event functions at
// the state of the last evaluation factor it again.
TEST(HeldRows, StuckJointAndRestingStopShareOneFactorization) {
  const double m1 = 1, c1 = 0.5, L1 = 1, m2 = 0.5, c2 = 0.4;
  for (double q1 : {0.3, -0.4, 1.1})
    for (double q2 : {-0.5, 0.2}) {
      auto l = LoadModel(DoublePendulum(q1, q2), {}, {}, true);
      ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
      const rt::Program& p = *l->prog;
      const std::vector<std::string> names = rt::StateNames(p);
      ASSERT_EQ(names.size(), 4u);
      std::vector<double> y(4);
      rt::InitialState(p, y.data());
      auto ws = rt::MakeWorkspace(p);
      sim::EndStopEvents stops(p, 0.0, 1e-12);  // rtol 0: the leave margin only round-off
      sim::StickSlipEvents stick(p);
      stick.SetStops(&stops);
      ASSERT_EQ(stick.Start(*ws, 0.0, y.data()), 0);  // (first: a free j1 would fall, pulling j2 off its stop)
      ASSERT_EQ(stick.Modes()[0], 0.0) << "j1 sticks";
      ASSERT_EQ(stops.Start(*ws, 0.0, y.data()), 0);
      ASSERT_EQ(stops.RestingSpeeds().size(), 1u) << "q1 = " << q1 << " q2 = " << q2;
      const double lambda2 = m2 * kG * c2 * std::cos(q1 + q2);
      const double tau1 = kG * ((m1 * c1 + m2 * L1) * std::cos(q1) + m2 * c2 * std::cos(q1 + q2));
      ASSERT_GT(lambda2, 0.0);  // it pushes: the stop holds
      // At a later time (a state not yet evaluated; the model does not depend on time).
      const double t = 0.5;
      const rt::EvalCounts before = rt::Counts(*ws);
      std::vector<double> ydot(4, 1.0);
      ASSERT_EQ(stick.Rhs(*ws, t, y.data(), ydot.data()), 0);
      EXPECT_EQ(rt::Counts(*ws).derivatives - before.derivatives, 1) << "one evaluation of the free accelerations";
      EXPECT_EQ(rt::Counts(*ws).inverse_mass_factorizations - before.inverse_mass_factorizations, 1)
          << "one factorization per evaluation";
      for (double v : ydot) EXPECT_EQ(v, 0.0);  // both joints held, at rest
      EXPECT_NEAR(stick.Modes()[1], tau1, 1e-12 * (1 + std::abs(tau1))) << "q1 = " << q1 << " q2 = " << q2;
      std::vector<double> g(static_cast<size_t>(stops.Count() + stick.Count()));
      ASSERT_EQ(stick.Functions(*ws, t, y.data(), g.data() + stops.Count()), 0);
      ASSERT_EQ(stops.Functions(*ws, t, y.data(), g.data()), 0);
      EXPECT_EQ(rt::Counts(*ws).inverse_mass_factorizations - before.inverse_mass_factorizations, 1)
          << "the event functions at the same state reuse it";
      EXPECT_NEAR(g[0], lambda2, 1e-12 * (1 + lambda2)) << "the stop's reaction (plus its round-off margin)";
      EXPECT_NEAR(g[1], 100.0 - std::abs(tau1), 1e-10) << "j1's margin to its static bound";
    }
}

// InverseMassColumns keeps the columns it solved for the kept factor (same t and q), and the
// M it factored (rt::KeptMassMatrix). If this fails, a column or M kept from another state is
// returned (the cache not dropped when q or t moved), or a kept column is not M^-1's
// (M x = e_k, M from rt::MassMatrix: an independent product), or a kept column or M differs
// in any bit from what a fresh workspace evaluates.
TEST(HeldRows, InverseMassColumnsKeptOnlyForTheirState) {
  auto l = LoadModel(DoublePendulum(0.3, -0.5), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const rt::Program& p = *l->prog;
  const size_t nu = 2;
  auto ws = rt::MakeWorkspace(p);
  const std::vector<std::vector<double>> states = {{0.3, -0.5, 0, 0}, {0.3, -0.5, 0, 0}, {1.2, 0.7, 0, 0}, {0.3, -0.5, 0, 0}};
  const std::vector<double> times = {0.0, 0.0, 0.0, 0.25};
  const std::vector<std::vector<int>> asked = {{1}, {0, 1}, {1, 0}, {0, 1}};
  for (size_t s = 0; s < states.size(); ++s) {
    const double t = times[s];
    const std::vector<double>& y = states[s];
    const std::vector<int>& ks = asked[s];
    std::vector<double> X(ks.size() * nu), fresh_X(ks.size() * nu), M(nu * nu);
    ASSERT_EQ(rt::InverseMassColumns(p, *ws, t, y.data(), ks.data(), static_cast<int>(ks.size()), X.data()), 0);
    auto fresh = rt::MakeWorkspace(p);
    ASSERT_EQ(rt::InverseMassColumns(p, *fresh, t, y.data(), ks.data(), static_cast<int>(ks.size()), fresh_X.data()), 0);
    ASSERT_EQ(rt::MassMatrix(p, *fresh, t, y.data(), M.data()), 0);
    for (size_t j = 0; j < ks.size(); ++j)
      for (size_t i = 0; i < nu; ++i) {
        EXPECT_EQ(X[j * nu + i], fresh_X[j * nu + i]) << "state " << s << " column " << ks[j] << " entry " << i;
        double Mx = 0.0;
        for (size_t k = 0; k < nu; ++k) Mx += M[k * nu + i] * X[j * nu + k];
        EXPECT_NEAR(Mx, i == static_cast<size_t>(ks[j]) ? 1.0 : 0.0, 1e-12) << "state " << s << " column " << ks[j];
      }
    std::vector<double> kept(nu * nu, -1.0);
    ASSERT_TRUE(rt::KeptMassMatrix(p, *ws, t, y.data(), kept.data())) << "state " << s;
    EXPECT_EQ(kept, M) << "state " << s;
    const std::vector<double> other = {y[0] + 0.1, y[1], 0, 0};
    EXPECT_FALSE(rt::KeptMassMatrix(p, *ws, t, other.data(), kept.data())) << "another q";
    EXPECT_FALSE(rt::KeptMassMatrix(p, *ws, t + 1.0, y.data(), kept.data())) << "another t";
  }
}

// A pendulum (j1: m = 1, centre c = 0.5 on x, I_zz = 0.1) resting on its stop q_min = 0
// under gravity (-y), with exact friction C = 1 (static C_s = 1.5) at j1 and a drive
// tau = 4 t pulling it off; beside it, a block on its own rail (s2, m = 1, friction 1, static
// 1.5) driven by 3 sin(10 t), which sticks and slips again and again. The stop and the
// friction hold j1 together until the pull passes gravity and the static friction,
//   4 t = m g c + C_s   ->   t_rel = (4.905 + 1.5) / 4 = 1.60125,
// one state: the stop's reaction 4.905 - 4 t crossing 0 (t = 1.22625) is no event, nor is any
// of the block's events. If this fails, j1 leaves its stop where the reaction turns (and is
// held by its friction as a second state: a leave and a rest whenever another joint's event
// re-solves the reactions and round-off flips the sign), moves before t_rel, or its release
// is not the static bound's.
TEST(HeldRows, PendulumHeldAtItsStopByFrictionIgnoresAnotherJointsEvents) {
  const std::string model =
      "model P\n"
      "  World world(g = {0, -9.81, 0});\n"
      "  Revolute j1(axis = {0, 0, 1}, q_min = 0, friction_torque = 1, friction_torque_s = 1.5, friction_exact = true);\n"
      "  Body b1(m = 1, r_CM = {0.5, 0, 0}, I = [0.001, 0, 0; 0, 0.1, 0; 0, 0, 0.1]);\n"
      "  Prismatic s2(axis = {1, 0, 0}, friction_force = 1, friction_force_s = 1.5, friction_exact = true);\n"
      "  Body b2(m = 1);\n"
      "equation\n"
      "  connect(world.frame_b, j1.frame_a);\n"
      "  connect(j1.frame_b, b1.frame_a);\n"
      "  connect(world.frame_b, s2.frame_a);\n"
      "  connect(s2.frame_b, b2.frame_a);\n"
      "  j1.tau = 4 * time;\n"
      "  s2.tau = 3 * sin(10 * time);\n"
      "end P;\n";
  auto l = LoadModel(model, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double t_rel = (1.0 * kG * 0.5 + 1.5) / 4.0;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 2.0, 0.05, {"j1.q"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    std::string log;
    std::vector<const sim::EventRecord*> j1;
    int s2_events = 0;
    for (const auto& ev : r.stats.events) {
      log += std::to_string(ev.time) + " " + ev.element + ": " + ev.kind + "\n";
      if (ev.element == "j1" && ev.time > 0.0) j1.push_back(&ev);
      if (ev.element == "s2" && ev.time < t_rel) ++s2_events;
    }
    EXPECT_GE(s2_events, 5) << how.name << "\n" << log;  // the block sticks and slips meanwhile
    ASSERT_EQ(j1.size(), 1u) << how.name << "\n" << log;
    EXPECT_EQ(j1[0]->kind.find("leaves q_min"), 0u) << how.name << "\n" << log;
    EXPECT_NEAR(j1[0]->time, t_rel, 1e-9) << how.name << "\n" << log;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      if (s.times[i] <= t_rel) {
        EXPECT_EQ(s.rows[i][0], 0.0) << how.name << " t = " << s.times[i];
      } else if (s.times[i] >= t_rel + 0.05) {
        EXPECT_GT(s.rows[i][0], 0.0) << how.name << " t = " << s.times[i];
      }
    }
  }
}

}  // namespace
}  // namespace kanesim::test
