// Coulomb friction (`mu`) in a when clause's speed jump beside constraint rows (issue 41,
// docs/events.md "Friction in a jump"): the rows' impulses keep A du = 0 and enter the
// joints' normal impulses. Each model starts where nothing accelerates (no gravity, no
// normal force: no friction before the jump), so the speeds before are the start values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Dense>

#include "sim/friction_impulse.h"
#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

// Speed `name` before or after the run's first event (its record; unchanged: `fallback`).
double Speed(const sim::SimResult& r, const std::string& name, bool after, double fallback) {
  for (const sim::EventChange& c : r.stats.events.at(0).changes)
    if (c.name == name) return after ? c.after : c.before;
  return fallback;
}

// Runs `text` over [0, 0.2] (its clause fires at 0.1); false (with a failure) if it does not.
bool RunOnce(const std::string& text, sim::SimResult* r, std::vector<double>* first_row = nullptr,
         const std::vector<std::string>& signals = {}) {
  auto l = LoadModel(text, {}, {}, true);
  EXPECT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  if (!l || !l->prog) return false;
  sim::MemorySink s = RunWith(*l->prog, AllIntegrators()[0], 0.2, 0.1, signals, r, 1e-11);
  EXPECT_EQ(r->status, sim::SimResult::Status::kOk) << r->message;
  if (first_row && !s.rows.empty()) *first_row = s.rows.front();
  return r->status == sim::SimResult::Status::kOk && !r->stats.events.empty();
}

// A carrier (m_c) on an x rail carries a gear pair: discs on j1 at its origin and on j2 2 m
// along x, centres on their axes (masses m1, m2, inertias I1, I2 about z), coupled
// u2 = -u1 / 2 (JointCoupling), friction mu1, mu2 with pin radii r1, r2; no gravity. Setting
// the carrier's speed from U to V gives each disc the impulse m_i (V - U) across its axis
// (the coupling's impulse is a torque: no force), N_i = m_i |V - U|. The reduced model of
// the gear: one rotation of inertia I = I1 + I2 / 4 whose friction is the joints' reflected
// through the ratio, at most C = mu1 r1 N1 + mu2 r2 N2 / 2: it sticks (u1+ = 0) where
// I |w| <= C, else slides on with u1+ = w - C sign(w) / I. A second model built that way
// (one joint of mu r m1 = mu1 r1 m1 + mu2 r2 m2 / 2 carrying I, m2 fixed on the carrier)
// takes the same jump.
constexpr double kMc = 1.5, kM1 = 2.0, kM2 = 3.0, kI1 = 0.3, kI2 = 0.8, kMu1 = 0.4, kMu2 = 0.6, kR1 = 0.05,
                 kR2 = 0.08;

std::string GearOnCarrier(double U, double w, double V, bool reduced) {
  const double mu_red = (kMu1 * kR1 * kM1 + 0.5 * kMu2 * kR2 * kM2) / (kR1 * kM1), I = kI1 + 0.25 * kI2;
  auto disc = [](const std::string& name, double m, double i) {
    return "  Body " + name + "(m = " + Num(m) + ", I = diagonal({" + Num(i) + ", " + Num(i) + ", " + Num(i) + "}));\n";
  };
  std::string t = "model G\n  World world(g = {0, 0, 0});\n  Prismatic rail(axis = {1, 0, 0}, u(start = " + Num(U) +
                  "));\n  Body carrier(m = " + Num(kMc) + ");\n";
  if (reduced) {
    t += "  Revolute j1(axis = {0, 0, 1}, u(start = " + Num(w) + "), mu = " + Num(mu_red) +
         ", friction_radius = " + Num(kR1) + ");\n" + disc("d1", kM1, I) + disc("d2", kM2, 0.0) +
         "equation\n  connect(carrier.frame_a, d2.frame_a);\n";
  } else {
    t += "  Revolute j1(axis = {0, 0, 1}, u(start = " + Num(w) + "), mu = " + Num(kMu1) + ", friction_radius = " +
         Num(kR1) + ");\n" + disc("d1", kM1, kI1) + "  FixedTranslation base(r = {2, 0, 0});\n" +
         "  Revolute j2(axis = {0, 0, 1}, mu = " + Num(kMu2) + ", friction_radius = " + Num(kR2) + ");\n" +
         disc("d2", kM2, kI2) + "  JointCoupling gear(ratio = -0.5);\nequation\n" +
         "  connect(carrier.frame_a, base.frame_a);\n  connect(base.frame_b, j2.frame_a);\n"
         "  connect(j2.frame_b, d2.frame_a);\n  connect(j1.drive, gear.flange_a);\n  connect(j2.drive, gear.flange_b);\n";
  }
  return t + "  connect(world.frame_b, rail.frame_a);\n  connect(rail.frame_b, carrier.frame_a);\n"
             "  connect(carrier.frame_a, j1.frame_a);\n  connect(j1.frame_b, d1.frame_a);\n"
             "  when time > 0.1 then\n    reinit(rail.u, " + Num(V) + ");\n  end when;\nend G;\n";
}

// If this fails, a reinit with mu in a mechanism with a coupling is refused (K321, before
// this change), the gear's two stuck joints (tied by the coupling) are not held by their
// friction together, the normal impulses miss the coupling, or the speeds after the jump
// leave the coupling's row (residual above 1e-12), or energy rises where the carrier stops.
TEST(WhenLoopFriction, GearedPairOnACarrierEqualsTheReducedModelWithReflectedFriction) {
  const double I = kI1 + 0.25 * kI2;
  int stuck = 0, slid = 0;
  for (double U : {0.0, 1.0, -0.7})
    for (double w : {2.0, -1.0, 0.3})
      for (double V : {0.0, 3.0, -2.5, 1.2}) {
        if (V == U) continue;
        const double dV = std::abs(V - U), C = kMu1 * kR1 * kM1 * dV + 0.5 * kMu2 * kR2 * kM2 * dV;
        const double want = I * std::abs(w) <= C ? 0.0 : w - C * (w > 0 ? 1 : -1) / I;
        (want == 0.0 ? stuck : slid)++;
        for (bool reduced : {false, true}) {
          sim::SimResult r;
          ASSERT_TRUE(RunOnce(GearOnCarrier(U, w, V, reduced), &r)) << U << " " << w << " " << V << " " << reduced;
          EXPECT_EQ(Speed(r, "rail.u", false, NAN), U);
          EXPECT_EQ(Speed(r, "rail.u", true, NAN), V);
          const double w1 = Speed(r, "j1.u", true, w);
          EXPECT_NEAR(w1, want, 1e-10 * (1 + std::abs(w))) << U << " " << w << " " << V << " " << reduced;
          if (reduced) continue;
          const double w2 = Speed(r, "j2.u", true, -0.5 * w);
          EXPECT_LE(std::abs(w2 + 0.5 * w1), 1e-12) << "the coupling's row after the jump";
          if (want == 0.0) {
            EXPECT_EQ(w1, 0.0);
          }
          if (V == 0.0) {  // stopping the carrier: T+ <= T-
            const double T0 = 0.5 * (kMc + kM1 + kM2) * U * U + 0.5 * I * w * w, T1 = 0.5 * I * w1 * w1;
            EXPECT_LE(T1, T0 * (1 + 1e-14)) << U << " " << w;
          }
        }
      }
  EXPECT_GT(stuck, 3);
  EXPECT_GT(slid, 3);
}

// examples/fourbar.mech (crank a, coupler b, rocker c, ground d; uniform rods) at rest, no
// gravity, mounted on a carrier (m_c) on an x rail with friction mu (and mu on the rocker's
// pivot, inside the loop), the carrier moving at U. Setting the crank's rate to W moves the
// loop by the velocity equations a W e^{i t2} + b w3 e^{i t3} = c w4 e^{i t4}; its momentum
// relative to the carrier is W (px, py), px + i py = sum m v_cm per unit W. The rail takes
// the y impulse W py (its normal impulse N = |W py|) and along x the friction P:
//   M du_c + W px = P,  M = m_c + the rods' masses
// stick: du_c = -U with |P| <= mu N; slide s: P = -s mu N, s (U + du_c) >= 0.
constexpr double kA = 0.2, kB = 0.6, kC = 0.5, kMa = 0.5, kMb = 1.0, kMcr = 0.8, kCarrier = 1.2, kMuRail = 0.3;

std::string FourBarOnARail(double U, double W) {
  FourBarText bar;
  bar.omega0 = 0;
  bar.gravity = false;
  bar.rocker_mods = ", mu = 0.2, friction_radius = 0.03";
  bar.base = "carrier.frame_a";
  bar.decls = "  Prismatic rail(axis = {1, 0, 0}, u(start = " + Num(U) + "), mu = " + Num(kMuRail) +
              ");\n  Body carrier(m = " + Num(kCarrier) + ");\n";
  bar.connects = "  connect(world.frame_b, rail.frame_a);\n  connect(rail.frame_b, carrier.frame_a);\n";
  bar.equations = "  when time > 0.1 then\n    reinit(crank_pivot.u, " + Num(W) + ");\n  end when;\n";
  return bar.Text();
}

// The loop's rates per unit crank rate at absolute angles t2, t3, t4 (Cramer), and the rods'
// momentum per unit crank rate.
void LoopRates(double t2, double t3, double t4, double* w3, double* w4, double* px, double* py) {
  const double det = -kB * std::cos(t3) * kC * std::sin(t4) + kC * std::cos(t4) * kB * std::sin(t3);
  *w3 = (kA * std::cos(t2) * kC * std::sin(t4) - kC * std::cos(t4) * kA * std::sin(t2)) / det;
  *w4 = (-kB * std::cos(t3) * kA * std::sin(t2) + kA * std::cos(t2) * kB * std::sin(t3)) / det;
  // v_cm: crank (a/2) e2', coupler a e2' + (b/2) w3 e3', rocker (c/2) w4 e4' (e' = (-sin, cos)).
  *px = -(kMa * kA / 2 + kMb * kA) * std::sin(t2) - kMb * kB / 2 * *w3 * std::sin(t3) - kMcr * kC / 2 * *w4 * std::sin(t4);
  *py = (kMa * kA / 2 + kMb * kA) * std::cos(t2) + kMb * kB / 2 * *w3 * std::cos(t3) + kMcr * kC / 2 * *w4 * std::cos(t4);
}

// If this fails, a reinit with mu in a closed loop is refused (K321, before this change), the
// rail's normal impulse is not the loop's momentum jump across it (the loop's own impulses
// are internal), the rail sticks or slides against the hand-derived balance, or the speeds
// after the jump leave the loop's velocity constraints (residual above 1e-12).
TEST(WhenLoopFriction, FourBarOnARailSticksOrSlidesByTheMomentumBalance) {
  const double M = kCarrier + kMa + kMb + kMcr;
  int kinds[3] = {0, 0, 0};
  for (double U : {0.5, -0.2, 0.02})
    for (double W : {4.0, -3.0, 1.0}) {
      sim::SimResult r;
      std::vector<double> y0;
      ASSERT_TRUE(RunOnce(FourBarOnARail(U, W), &r, &y0, {"crank_pivot.q", "crank_coupler.q", "rocker_pivot.q"}));
      const double t2 = y0[0], t3 = y0[0] + y0[1], t4 = y0[2];
      double w3, w4, px, py;
      LoopRates(t2, t3, t4, &w3, &w4, &px, &py);
      const double N = std::abs(W * py);
      double want = NAN;  // the rail's speed after
      if (std::abs(-M * U + W * px) <= kMuRail * N) want = 0.0;
      for (double s : {1.0, -1.0})
        if (std::isnan(want) && s * (U + (-s * kMuRail * N - W * px) / M) > 0) want = U + (-s * kMuRail * N - W * px) / M;
      ASSERT_FALSE(std::isnan(want)) << U << " " << W;
      ++kinds[want == 0.0 ? 0 : want > 0 ? 1 : 2];
      EXPECT_EQ(Speed(r, "rail.u", false, NAN), U);
      const double uc = Speed(r, "rail.u", true, U);
      EXPECT_NEAR(uc, want, 1e-10 * (1 + std::abs(U))) << "U = " << U << ", W = " << W;
      if (want == 0.0) {
        EXPECT_EQ(uc, 0.0);
      }
      EXPECT_EQ(Speed(r, "crank_pivot.u", true, NAN), W);
      const double u3 = W + Speed(r, "crank_coupler.u", true, 0.0), u4 = Speed(r, "rocker_pivot.u", true, 0.0);
      EXPECT_NEAR(u3, W * w3, 1e-10 * std::abs(W));
      EXPECT_NEAR(u4, W * w4, 1e-10 * std::abs(W));
      const double rx = -kA * W * std::sin(t2) - kB * u3 * std::sin(t3) + kC * u4 * std::sin(t4);
      const double ry = kA * W * std::cos(t2) + kB * u3 * std::cos(t3) - kC * u4 * std::cos(t4);
      EXPECT_LE(std::hypot(rx, ry), 1e-12) << "the loop's velocity constraints after the jump";
    }
  EXPECT_GT(kinds[0], 0);
  EXPECT_GT(kinds[1], 0);
  EXPECT_GT(kinds[2], 0);
}


// The four-bar at rest on the ground (no gravity, d = 0.6), mu on the coupler's pin
// (crank_coupler) and the rocker's pivot, its crank's rate set to W (sim::FrictionJump with
// the row e_crank). Planar Newton-Euler of the three rods in impulses, the unknowns the four
// pins' impulses R1 (ground on crank), R2 (crank on coupler), R3 (coupler on rocker, the cut
// joint's), R4 (ground on rocker) and the reinit's c:
//   crank   m_a dv_a = R1 - R2   I_a dw2 = c - t_cc + (O2 - G_a) x R1 - (A - G_a) x R2
//   coupler m_b dv_b = R2 - R3   I_b dw3 = t_cc + (A - G_b) x R2 - (B - G_b) x R3
//   rocker  m_c dv_c = R4 + R3   I_c dw4 = t_4 + (O4 - G_c) x R4 + (B - G_c) x R3
// (I = m L^2 / 12), the joints sliding (one degree of freedom: the rates follow W), their
// friction impulses t_cc = -mu r |R2| sign(W (w3 - 1)), t_4 = -mu r |R4| sign(W w4) solved
// by fixed-point iteration. The normal impulses are the pins' impulses on each joint's
// subtree: R2 (coupler) and R4 (rocker), R2 carrying the cut joint's R3.
// If this fails, the loop's impulses do not enter the normal impulses (or the friction, the
// reinit's impulse or the jump disagree with Newton-Euler).
TEST(WhenLoopFriction, FourBarImpulsesMatchNewtonEulerWithTheCutJointsImpulse) {
  const double d = 0.6, mu = 0.3, r = 0.05, W = 3.0;
  FourBarText bar;
  bar.omega0 = 0;
  bar.gravity = false;
  bar.rocker_mods = bar.coupler_mods = ", mu = " + Num(mu) + ", friction_radius = " + Num(r);
  const std::string text = bar.Text();
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const rt::Program& p = *l->prog;
  const std::vector<std::string> names = rt::StateNames(p);
  auto at = [&](const std::string& n) { return static_cast<int>(std::find(names.begin(), names.end(), n) - names.begin()); };
  const int nq = rt::NumQ(p), nu = rt::NumU(p);
  std::vector<double> y(names.size());
  rt::InitialState(p, y.data());
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> J(static_cast<size_t>(nu), 0.0);
  J[static_cast<size_t>(at("crank_pivot.u") - nq)] = 1.0;
  sim::FrictionJumpResult res;
  std::string why;
  ASSERT_EQ(sim::FrictionJump(p, *ws, 0.0, y.data(), J, {W}, &res, &why), 0) << why;

  const double t2 = y[static_cast<size_t>(at("crank_pivot.q"))];
  const double t3 = t2 + y[static_cast<size_t>(at("crank_coupler.q"))], t4 = y[static_cast<size_t>(at("rocker_pivot.q"))];
  double w3, w4, px, py;
  LoopRates(t2, t3, t4, &w3, &w4, &px, &py);
  auto e = [](double t) { return Eigen::Vector2d(std::cos(t), std::sin(t)); };
  auto ep = [](double t) { return Eigen::Vector2d(-std::sin(t), std::cos(t)); };
  const Eigen::Vector2d O2(0, 0), A = kA * e(t2), Ga = kA / 2 * e(t2), Gb = A + kB / 2 * e(t3), B = A + kB * e(t3);
  const Eigen::Vector2d O4(d, 0), Gc = O4 + kC / 2 * e(t4);
  const Eigen::Vector2d dva = W * kA / 2 * ep(t2), dvb = W * (kA * ep(t2) + kB / 2 * w3 * ep(t3)),
                        dvc = W * kC / 2 * w4 * ep(t4);
  const double Ia = kMa * kA * kA / 12, Ib = kMb * kB * kB / 12, Ic = kMcr * kC * kC / 12;
  double tcc = 0.0, t4f = 0.0;
  Eigen::VectorXd x;  // R1, R2, R3, R4 (x, y each), c
  for (int it = 0; it < 100; ++it) {
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(9, 9);
    Eigen::VectorXd rhs(9);
    auto force = [&](int row, int R, double sign) {  // sign R_R into the momentum rows row, row + 1
      E(row, 2 * R) += sign, E(row + 1, 2 * R + 1) += sign;
    };
    auto moment = [&](int row, int R, const Eigen::Vector2d& arm, double sign) {  // sign arm x R_R
      E(row, 2 * R) += -sign * arm.y(), E(row, 2 * R + 1) += sign * arm.x();
    };
    force(0, 0, 1), force(0, 1, -1), rhs.segment<2>(0) = kMa * dva;
    moment(2, 0, O2 - Ga, 1), moment(2, 1, A - Ga, -1), E(2, 8) = 1, rhs[2] = Ia * W + tcc;
    force(3, 1, 1), force(3, 2, -1), rhs.segment<2>(3) = kMb * dvb;
    moment(5, 1, A - Gb, 1), moment(5, 2, B - Gb, -1), rhs[5] = Ib * W * w3 - tcc;
    force(6, 3, 1), force(6, 2, 1), rhs.segment<2>(6) = kMcr * dvc;
    moment(8, 3, O4 - Gc, 1), moment(8, 2, B - Gc, 1), rhs[8] = Ic * W * w4 - t4f;
    x = E.fullPivLu().solve(rhs);
    const double tcc1 = -mu * r * x.segment<2>(2).norm() * (W * (w3 - 1) > 0 ? 1 : -1);
    const double t41 = -mu * r * x.segment<2>(6).norm() * (W * w4 > 0 ? 1 : -1);
    const bool done = std::abs(tcc1 - tcc) + std::abs(t41 - t4f) < 1e-16;
    tcc = tcc1, t4f = t41;
    if (done) break;
  }
  const std::vector<rt::FrictionJoint> fj = rt::FrictionJoints(p);
  ASSERT_EQ(fj.size(), 2u);
  for (size_t i = 0; i < fj.size(); ++i) {
    const bool rocker = fj[i].joint == "rocker_pivot";
    const double N = (rocker ? x.segment<2>(6) : x.segment<2>(2)).norm();
    EXPECT_NEAR(res.normal[i], N, 1e-10 * N) << fj[i].joint;
    EXPECT_NEAR(res.friction[i], rocker ? t4f : tcc, 1e-10 * N * mu * r) << fj[i].joint;
  }
  EXPECT_NEAR(res.impulse.at(0), x[8], 1e-10 * std::abs(x[8]));
  EXPECT_TRUE(res.stuck.empty());
  EXPECT_NEAR(res.du[static_cast<size_t>(at("rocker_pivot.u") - nq)], W * w4, 1e-12);
  EXPECT_NEAR(res.du[static_cast<size_t>(at("crank_coupler.u") - nq)], W * (w3 - 1), 1e-12);
  // The friction changes the reinit's impulse by its work per unit crank rate (virtual work).
  EXPECT_NEAR(x[8] + tcc * (w3 - 1) + t4f * w4, (Ia + kMa * kA * kA / 4) * W +
                  kMb * (kA * ep(t2) + kB / 2 * w3 * ep(t3)).squaredNorm() * W + Ib * w3 * w3 * W +
                  (Ic + kMcr * kC * kC / 4) * w4 * w4 * W, 1e-10 * std::abs(x[8]));
  (void)px, (void)py;
}


// The four-bar on its carrier (FourBarOnARail, the rail without friction), its crank turning
// at w0, mu only on the rocker's pivot (radius r), the carrier stopped from U (the row
// e_rail, target -U; sim::FrictionJump at the start state). Newton-Euler of the rods as in
// the test above, their mass-centre jumps now du_c e_x + dw v_rel (v_rel per unit crank
// rate), the crank's pivot free: unknowns R1..R4 and either dw (sliding: t_4 = -mu r |R4|
// sign(w4 (w0 + dw)), fixed point) or t_4 (stuck: dw = -w0, held while |t_4| <= mu r |R4|).
// Energy: T- = M U^2 / 2 + U w0 px + Mr w0^2 / 2, T+ = Mr (w0 + dw)^2 / 2 (Mr the loop's
// inertia about the crank), never above T-.
// If this fails, the loop does not stick by its pivot's friction where Newton-Euler holds it,
// slides by another impulse, or the jump raises the energy.
TEST(WhenLoopFriction, FourBarStoppedWithItsCarrierSticksOrSlidesByNewtonEuler) {
  const double d = 0.6, mu = 0.5, r = 0.2;
  int kinds[2] = {0, 0};
  const double free = -2.9259073;  // w0 / U for which the free jump stops the loop (-px / Mr, by hand)
  for (double U : {2.0, -1.0, 0.3})
    for (double w0 : {1.0, -4.0, 0.97 * free * U, 1.1 * free * U}) {
      std::string text = FourBarOnARail(U, 1.0);
      auto put = [&](const std::string& from, const std::string& to) {
        ASSERT_NE(text.find(from), std::string::npos) << from;
        text.replace(text.find(from), from.size(), to);
      };
      put("\"rad/s\") = 0", "\"rad/s\") = " + Num(w0));
      put(", mu = " + Num(kMuRail), "");
      put("mu = 0.2, friction_radius = 0.03", "mu = " + Num(mu) + ", friction_radius = " + Num(r));
      auto l = LoadModel(text, {}, {}, true);
      ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
      const rt::Program& p = *l->prog;
      const std::vector<std::string> names = rt::StateNames(p);
      auto at = [&](const std::string& n) { return static_cast<size_t>(std::find(names.begin(), names.end(), n) - names.begin()); };
      const auto nq = static_cast<size_t>(rt::NumQ(p)), nu = static_cast<size_t>(rt::NumU(p));
      std::vector<double> y(names.size());
      rt::InitialState(p, y.data());
      ASSERT_NEAR(y[at("crank_pivot.u")], w0, 1e-12);
      ASSERT_NEAR(y[at("rail.u")], U, 1e-12);
      auto ws = rt::MakeWorkspace(p);
      std::vector<double> J(nu, 0.0);
      J[at("rail.u") - nq] = 1.0;
      sim::FrictionJumpResult res;
      std::string why;
      ASSERT_EQ(sim::FrictionJump(p, *ws, 0.0, y.data(), J, {-U}, &res, &why), 0) << why;

      const double t2 = y[at("crank_pivot.q")], t3 = t2 + y[at("crank_coupler.q")], t4 = y[at("rocker_pivot.q")];
      double w3, w4, px, py;
      LoopRates(t2, t3, t4, &w3, &w4, &px, &py);
      auto e = [](double t) { return Eigen::Vector2d(std::cos(t), std::sin(t)); };
      auto ep = [](double t) { return Eigen::Vector2d(-std::sin(t), std::cos(t)); };
      const Eigen::Vector2d O2(0, 0), A = kA * e(t2), Ga = kA / 2 * e(t2), Gb = A + kB / 2 * e(t3), B = A + kB * e(t3);
      const Eigen::Vector2d O4(d, 0), Gc = O4 + kC / 2 * e(t4), ex(1, 0);
      const Eigen::Vector2d va = kA / 2 * ep(t2), vb = kA * ep(t2) + kB / 2 * w3 * ep(t3), vc = kC / 2 * w4 * ep(t4);
      const double Ia = kMa * kA * kA / 12, Ib = kMb * kB * kB / 12, Ic = kMcr * kC * kC / 12, dU = -U;
      // stick: z = t_4 (dw = -w0); slide: z = dw with t_4 given.
      auto solve = [&](bool stick, double t4f) {
        Eigen::MatrixXd E = Eigen::MatrixXd::Zero(9, 9);
        Eigen::VectorXd rhs = Eigen::VectorXd::Zero(9);
        auto force = [&](int row, int R, double sign) { E(row, 2 * R) += sign, E(row + 1, 2 * R + 1) += sign; };
        auto moment = [&](int row, int R, const Eigen::Vector2d& arm, double sign) {
          E(row, 2 * R) += -sign * arm.y(), E(row, 2 * R + 1) += sign * arm.x();
        };
        force(0, 0, 1), force(0, 1, -1), moment(2, 0, O2 - Ga, 1), moment(2, 1, A - Ga, -1);
        force(3, 1, 1), force(3, 2, -1), moment(5, 1, A - Gb, 1), moment(5, 2, B - Gb, -1);
        force(6, 3, 1), force(6, 2, 1), moment(8, 3, O4 - Gc, 1), moment(8, 2, B - Gc, 1);
        const double m[3] = {kMa, kMb, kMcr}, I[3] = {Ia, Ib, Ic}, w[3] = {1.0, w3, w4};
        const Eigen::Vector2d v[3] = {va, vb, vc};
        for (int k = 0; k < 3; ++k) {
          rhs.segment<2>(3 * k) = m[k] * dU * ex;
          if (stick) {
            rhs.segment<2>(3 * k) += m[k] * -w0 * v[k];
            rhs[3 * k + 2] = I[k] * w[k] * -w0;
          } else {
            E.block<2, 1>(3 * k, 8) = -m[k] * v[k];
            E(3 * k + 2, 8) = -I[k] * w[k];
          }
        }
        if (stick) E(8, 8) = 1.0;
        else rhs[8] = -t4f;
        return Eigen::VectorXd(E.fullPivLu().solve(rhs));
      };
      Eigen::VectorXd x = solve(true, 0.0);
      double dw = -w0, t4f = x[8];
      const bool stuck = std::abs(t4f) <= mu * r * x.segment<2>(6).norm();
      if (!stuck) {
        t4f = 0.0;
        for (int it = 0; it < 200; ++it) {
          x = solve(false, t4f);
          const double next = -mu * r * x.segment<2>(6).norm() * (w4 * (w0 + x[8]) > 0 ? 1 : -1);
          const bool done = std::abs(next - t4f) < 1e-15;
          t4f = next;
          if (done) break;
        }
        x = solve(false, t4f);
        dw = x[8];
        ASSERT_GT(w4 * (w0 + dw) * (t4f < 0 ? 1 : -1), 0.0) << "the slide's sign";
      }
      ++kinds[stuck ? 0 : 1];
      const size_t rocker = rt::FrictionJoints(p).at(0).joint == "rocker_pivot" ? 0 : 1;
      EXPECT_NEAR(res.du[at("crank_pivot.u") - nq], dw, 1e-10 * (1 + std::abs(w0))) << "U = " << U << ", w0 = " << w0;
      EXPECT_NEAR(res.friction.at(rocker), t4f, 1e-10 * (1 + std::abs(t4f))) << "U = " << U << ", w0 = " << w0;
      EXPECT_EQ(res.stuck.size(), stuck ? 1u : 0u) << "U = " << U << ", w0 = " << w0;
      const double Mr = Ia + kMa * kA * kA / 4 + kMb * vb.squaredNorm() + Ib * w3 * w3 + (Ic + kMcr * kC * kC / 4) * w4 * w4;
      const double M = kCarrier + kMa + kMb + kMcr;
      const double T0 = 0.5 * M * U * U + U * w0 * px + 0.5 * Mr * w0 * w0, T1 = 0.5 * Mr * (w0 + dw) * (w0 + dw);
      EXPECT_LE(T1, T0 * (1 + 1e-14)) << "U = " << U << ", w0 = " << w0;
    }
  EXPECT_GT(kinds[0], 0);
  EXPECT_GT(kinds[1], 0);
}

}  // namespace
}  // namespace kanesim::test
