// kanesim linearize (linearize) against closed forms, the nonlinear model, and the
// other formulation.
//
// Pendulum, point mass m at distance l:           lambda = +-i sqrt(g / l)                (1)
// Double pendulum of uniform rods (m = L = 1), hanging, absolute angles:
//   M = [[4/3, 1/2], [1/2, 1/3]],  K = g diag(3/2, 1/2),  det(K - w^2 M) = 0
//   => 7 w^4 - 42 g w^2 + 27 g^2 = 0,  w^2 = g (3 -+ 6 / sqrt(7))                        (2)
// Spring-mass-damper:  A = [[0, 1], [-k/m, -c/m]],  B(force) = [0; 1/m]                  (3)
// Four-bar (examples/fourbar.mech) about its equilibrium: the crank angle theta, the
// loop closed in closed form (circle intersection), V(theta) and M(theta) from it:
//   lambda^2 = -V''(theta*) / M(theta*),  V'(theta*) = 0                                (4)
// Upright thin disk (radius a, I_axis = m a^2 / 2, I_diam = m a^2 / 4) rolling at speed v,
// spin W = v / a (linearized lean equation; Kane & Levinson 1985, ch. 5; Neimark & Fufaev):
//   lambda^2 = (4 g / a - 12 W^2) / 5,  stable above v = sqrt(g a / 3)                    (5)
// Sleeping heavy symmetric top (mass m, centre at l above the pivot, axial moment C,
// transverse moment A about the pivot, spin s), small tilts z = alpha + i beta:
//   A z'' - i C s z' - m g l z = 0,  lambda = i (C s +- sqrt(C^2 s^2 - 4 A m g l)) / (2 A)
// and conjugates: stable (all imaginary) for C^2 s^2 > 4 A m g l (Klein & Sommerfeld;
// Goldstein, Classical Mechanics, sec. 5.7)                                              (6)
#include <gtest/gtest.h>

#include <unsupported/Eigen/MatrixFunctions>
#include <algorithm>
#include <cmath>
#include <complex>

#include "linearize/linearize.h"
#include "runtime/program/program.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;

int FreeQ(const rt::Program& p, const std::string& joint, int k = 0) {
  for (const rt::TreeJoint& j : p.joints)
    if (j.name == joint)
      for (int i = 0; i < p.nq; ++i)
        if (p.q_free[static_cast<size_t>(i)] == j.q0 + k) return i;
  ADD_FAILURE() << "no free coordinate of " << joint;
  return 0;
}

lin::LinearModel LinearizeAt(const rt::Program& p, const lin::OperatingPoint& op, lin::LinearizeOptions o = {}) {
  lin::LinearModel m;
  const lin::Status s = lin::Linearize(p, op, o, &m);
  EXPECT_TRUE(s.ok()) << s.message;
  lin::ComputeModes(&m);
  return m;
}

// The eigenvalues whose modulus exceeds `floor`, sorted by imaginary part, then real.
std::vector<std::complex<double>> NonZero(const lin::LinearModel& m, double floor = 1e-6) {
  std::vector<std::complex<double>> v;
  for (const lin::Mode& md : m.modes)
    if (std::abs(md.lambda) > floor) v.push_back(md.lambda);
  std::sort(v.begin(), v.end(), [](auto a, auto b) { return a.imag() != b.imag() ? a.imag() < b.imag() : a.real() < b.real(); });
  return v;
}

const std::string kPendulum = kRoot + "/tests/linearize/models/pendulum.mech";

TEST(Linearize, PendulumIsPlusMinusISqrtGOverL) {
  // If this fails, the state derivative's differences, the chart or the eigenvalue
  // sorting are wrong.
  auto l = LoadModel(kPendulum);
  ASSERT_TRUE(l && l->prog);
  lin::LinearizeOptions o;
  o.inputs = {"hinge.tau"};
  o.outputs = {"hinge.q", "tip_y"};
  const lin::LinearModel m = LinearizeAt(*l->prog, lin::StartPoint(*l->prog), o);
  ASSERT_EQ(m.states, (std::vector<std::string>{"hinge.q", "hinge.u"}));
  const double w = std::sqrt(kG / 0.7);  // (1)
  ASSERT_EQ(m.modes.size(), 2u);
  EXPECT_NEAR(m.modes[0].lambda.imag(), w, 1e-9 * w);
  EXPECT_NEAR(m.modes[1].lambda.imag(), -w, 1e-9 * w);
  EXPECT_NEAR(m.modes[0].lambda.real(), 0.0, 1e-9 * w);
  EXPECT_NEAR(m.modes[0].zeta, 0.0, 1e-9);
  EXPECT_NEAR(m.modes[0].freq_hz, w / (2 * M_PI), 1e-9);
  EXPECT_EQ(m.modes[0].dominant.front().first, "hinge.q");
  EXPECT_LT(m.error_A, 1e-9);
  EXPECT_LT(m.unsteady, 1e-12);  // an equilibrium: f(0) = 0
  // B: a torque on the hinge accelerates by 1 / (m l^2). C: q and the bob's height
  // (d y / d q = l cos(q) = 0 at q = -pi/2, hence 0).
  EXPECT_NEAR(m.B(1, 0), 1.0 / (2 * 0.49), 1e-12);
  EXPECT_NEAR(m.B(0, 0), 0.0, 1e-12);
  EXPECT_NEAR(m.C(0, 0), 1.0, 1e-10);
  EXPECT_NEAR(m.C(1, 0), 0.0, 1e-10);
  EXPECT_NEAR(m.D(0, 0), 0.0, 1e-12);
}

TEST(Linearize, PendulumEquilibriumFromAnOffsetStart) {
  // If this fails, the Newton search on the accelerations or its report is wrong.
  auto l = LoadModel(kPendulum);
  ASSERT_TRUE(l && l->prog);
  lin::OperatingPoint op = lin::StartPoint(*l->prog);
  op.y[0] += 0.4;
  lin::EquilibriumResult eq;
  const lin::Status s = lin::FindEquilibrium(*l->prog, op, &eq);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_NEAR(eq.point.y[0], -M_PI / 2, 1e-10);
  EXPECT_LT(eq.residual, 1e-8);
  ASSERT_EQ(eq.moved.size(), 1u);
  EXPECT_EQ(eq.moved[0].first, "hinge.q");
  EXPECT_NEAR(eq.moved[0].second, -0.4, 1e-10);
}

TEST(Linearize, PendulumUnderAConstantTorqueAboveMglHasNoEquilibrium) {
  // If this fails, a stalled Newton search is reported as an equilibrium.
  auto l = LoadModel(kPendulum, {{"tau0", "20"}});  // m g l = 13.7 < 20
  ASSERT_TRUE(l && l->prog);
  lin::EquilibriumResult eq;
  const lin::Status s = lin::FindEquilibrium(*l->prog, lin::StartPoint(*l->prog), &eq);
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.message.find("no equilibrium found"), std::string::npos) << s.message;
}

// examples/double_pendulum.mech with its start angles as parameters.
const char* kDoublePendulum = R"(
model DP
  parameter Real th1 = -pi / 2;
  parameter Real th2 = 0;
  World world(g = {0, -9.81, 0});
  Revolute shoulder(axis = {0, 0, 1}, q(start = th1), u(start = 0));
  Rod rod1(L = 1, m = 1);
  Revolute elbow(axis = {0, 0, 1}, q(start = th2), u(start = 0));
  Rod rod2(L = 1, m = 1);
equation
  connect(world.frame_b, shoulder.frame_a);
  connect(shoulder.frame_b, rod1.frame_a);
  connect(rod1.frame_b, elbow.frame_a);
  connect(elbow.frame_b, rod2.frame_a);
end DP;
)";

TEST(Linearize, ChainEquilibriumAfterNewtonStallsIsTheHangingOne) {
  // If this fails, the relaxation that takes over when Newton stalls (a 10-link spatial
  // chain bent 0.1 rad at every joint, nearly horizontal) does not reach the hanging
  // chain: potential -m g L sum(i - 1/2) = -245.25 J (m = 1, L = 0.5), every eigenvalue
  // on the imaginary axis.
  auto l = LoadModel(kRoot + "/examples/chain.mech");
  ASSERT_TRUE(l && l->prog);
  lin::EquilibriumResult eq;
  const lin::Status s = lin::FindEquilibrium(*l->prog, lin::StartPoint(*l->prog), &eq);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_GT(eq.relaxation_steps, 0);
  std::string err;
  auto plan = rt::PlanSignals(*l->prog, {"potential_energy"}, &err);
  ASSERT_TRUE(plan) << err;
  auto ws = rt::MakeWorkspace(*l->prog);
  double V = 0.0;
  ASSERT_EQ(rt::EvalSignals(*l->prog, *plan, *ws, eq.point.t, eq.point.y.data(), &V), 0);
  EXPECT_NEAR(V, -kG * 0.5 * 50, 1e-9);
  const lin::LinearModel m = LinearizeAt(*l->prog, eq.point);
  for (const lin::Mode& md : m.modes) EXPECT_NEAR(md.lambda.real(), 0.0, 1e-6);
}

TEST(Linearize, DoublePendulumMatchesTheTwoByTwoGeneralizedEigenproblem) {
  // If this fails, coupled inertia or gravity stiffness is linearized wrongly.
  auto l = LoadModel(kDoublePendulum, {}, {}, true);
  ASSERT_TRUE(l && l->prog);
  const lin::LinearModel m = LinearizeAt(*l->prog, lin::StartPoint(*l->prog));
  const auto ev = NonZero(m);
  ASSERT_EQ(ev.size(), 4u);
  const double w2_lo = kG * (3 - 6 / std::sqrt(7.0)), w2_hi = kG * (3 + 6 / std::sqrt(7.0));  // (2)
  EXPECT_NEAR(ev[0].imag(), -std::sqrt(w2_hi), 1e-9 * std::sqrt(w2_hi));
  EXPECT_NEAR(ev[1].imag(), -std::sqrt(w2_lo), 1e-9 * std::sqrt(w2_lo));
  EXPECT_NEAR(ev[2].imag(), std::sqrt(w2_lo), 1e-9 * std::sqrt(w2_lo));
  EXPECT_NEAR(ev[3].imag(), std::sqrt(w2_hi), 1e-9 * std::sqrt(w2_hi));
  for (const auto& e : ev) EXPECT_NEAR(e.real(), 0.0, 1e-8);
}

TEST(Linearize, SpringMassDamperIsExact) {
  // If this fails, damping, the joint-force input, a parameter input or the outputs are
  // linearized wrongly (the model is linear: A, B, C, D are exact).
  auto l = LoadModel(kRoot + "/examples/spring_mass.mech", {{"F0", "0"}});
  ASSERT_TRUE(l && l->prog);
  lin::LinearizeOptions o;
  o.inputs = {"slider.tau", "k"};
  o.outputs = {"slider.q", "slider.u"};
  const lin::LinearModel m = LinearizeAt(*l->prog, lin::StartPoint(*l->prog), o);
  const double mass = 2, k = 50, c = 1, q0 = 0.1;
  Eigen::Matrix2d A;
  A << 0, 1, -k / mass, -c / mass;  // (3)
  EXPECT_LT((m.A - A).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(m.B(1, 0), 1 / mass, 1e-12);
  EXPECT_NEAR(m.B(1, 1), -q0 / mass, 1e-9);  // d/dk of -k q / m at q0
  EXPECT_LT((m.C - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT(m.D.cwiseAbs().maxCoeff(), 1e-12);
  const double wd = std::sqrt(k / mass - std::pow(c / (2 * mass), 2));
  ASSERT_EQ(m.modes.size(), 2u);
  EXPECT_NEAR(m.modes[0].lambda.real(), -c / (2 * mass), 1e-9);
  EXPECT_NEAR(m.modes[0].lambda.imag(), wd, 1e-9);
  EXPECT_NEAR(m.modes[0].zeta, c / (2 * std::sqrt(k * mass)), 1e-9);
  // Not an equilibrium (q0 = 0.1), but a linear model: A does not change along the motion.
  EXPECT_LT(m.unsteady, 1e-6);
}

// Four-bar in closed form: absolute link angles for crank angle th on the open branch.
struct FourBarGeom {
  double a = 0.2, b = 0.6, c = 0.5, d = 0.6, m1 = 0.5, m2 = 1.0, m3 = 0.8;
  // Points: O = 0, A = crank tip, B = coupler-rocker pin, D = (d, 0).
  void Points(double th, Eigen::Vector2d* A, Eigen::Vector2d* B) const {
    *A = Eigen::Vector2d(a * std::cos(th), a * std::sin(th));
    const Eigen::Vector2d D(d, 0), AD = D - *A;
    const double L = AD.norm(), x = (b * b - c * c + L * L) / (2 * L), h = std::sqrt(b * b - x * x);
    const Eigen::Vector2d e = AD / L, n(-e.y(), e.x());
    *B = *A + x * e + h * n;  // the branch with B to the left of A -> D (above the ground link)
  }
  double V(double th) const {
    Eigen::Vector2d A, B;
    Points(th, &A, &B);
    return kG * (m1 * A.y() / 2 + m2 * (A.y() + B.y()) / 2 + m3 * B.y() / 2);
  }
  // Generalized mass for the crank rate: sum of m v_cm^2 + I w^2 per unit crank rate.
  double M(double th) const {
    const double h = 1e-6;
    Eigen::Vector2d Ap, Bp, Am, Bm;
    Points(th + h, &Ap, &Bp);
    Points(th - h, &Am, &Bm);
    const Eigen::Vector2d dA = (Ap - Am) / (2 * h), dB = (Bp - Bm) / (2 * h), D(d, 0);
    auto ang = [](Eigen::Vector2d v) { return std::atan2(v.y(), v.x()); };
    const double dphi = (ang(Bp - Ap) - ang(Bm - Am)) / (2 * h), dpsi = (ang(Bp - D) - ang(Bm - D)) / (2 * h);
    return m1 * a * a / 3 + m2 * ((dA + dB) / 2).squaredNorm() + m2 * b * b / 12 * dphi * dphi +
           m3 * c * c / 3 * dpsi * dpsi;
  }
};

TEST(Linearize, FourBarAboutItsEquilibriumMatchesTheOneDofClosedForm) {
  // If this fails, the dependent coordinates of a loop (Newton on phi = 0), its dependent
  // speeds, or the equilibrium search on a looped mechanism are wrong.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  lin::EquilibriumResult eq;
  const lin::Status s = lin::FindEquilibrium(*l->prog, lin::StartPoint(*l->prog), &eq);
  ASSERT_TRUE(s.ok()) << s.message;
  const lin::LinearModel m = LinearizeAt(*l->prog, eq.point);
  ASSERT_EQ(m.states.size(), 2u);  // one coordinate, one speed
  // The closed form's equilibrium: Newton on V'(th) from the crank angle found.
  FourBarGeom g;
  double th = eq.point.y[static_cast<size_t>(FreeQ(*l->prog, "crank_pivot"))];
  const double h = 1e-4;
  for (int it = 0; it < 20; ++it) {
    const double d1 = (g.V(th + h) - g.V(th - h)) / (2 * h), d2 = (g.V(th + h) - 2 * g.V(th) + g.V(th - h)) / (h * h);
    th -= d1 / d2;
  }
  EXPECT_NEAR(th, eq.point.y[static_cast<size_t>(FreeQ(*l->prog, "crank_pivot"))], 1e-7);
  const double V2 = (g.V(th + h) - 2 * g.V(th) + g.V(th - h)) / (h * h);
  const double lam2 = -V2 / g.M(th);  // (4)
  ASSERT_EQ(m.modes.size(), 2u);
  const std::complex<double> lam = m.modes[0].lambda;
  EXPECT_NEAR((lam * lam).real(), lam2, 1e-6 * std::abs(lam2));
  EXPECT_NEAR((lam * lam).imag(), 0.0, 1e-6 * std::abs(lam2));
}

TEST(Linearize, FourBarReducedAndMultiplierFormsAgree) {
  // If this fails, the linear model depends on how the equations are solved.
  rt::CompileOptions dense, sparse;
  dense.solver = rt::SolverPath::Dense;
  sparse.solver = rt::SolverPath::Sparse;
  auto ld = LoadModel(kRoot + "/examples/fourbar.mech", {}, dense);
  auto ls = LoadModel(kRoot + "/examples/fourbar.mech", {}, sparse);
  ASSERT_TRUE(ld && ld->prog && ls && ls->prog);
  ASSERT_EQ(ls->prog->solver, rt::SolverPath::Sparse);
  // About the moving start (crank at 6 rad/s): the same A either way.
  const lin::LinearModel md = LinearizeAt(*ld->prog, lin::StartPoint(*ld->prog));
  const lin::LinearModel ms = LinearizeAt(*ls->prog, lin::StartPoint(*ls->prog));
  ASSERT_EQ(md.states, ms.states);
  EXPECT_LT((md.A - ms.A).cwiseAbs().maxCoeff(), 1e-7 * std::max(1.0, md.A.cwiseAbs().maxCoeff()));
}

TEST(Linearize, UprightRollingDiskEigenvaluesAgainstSpeed) {
  // If this fails, rolling (speed-only) constraints are reduced wrongly, or the lean
  // mode of the thin disk does not follow the closed form (5) across its stability limit.
  const double a = 0.3, vc = std::sqrt(kG * a / 3);
  for (double v : {0.3, 0.8, 1.2, 2.0, 4.0}) {
    auto l = LoadModel(kRoot + "/examples/rolling_disk_upright.mech", {{"v", std::to_string(v)}});
    ASSERT_TRUE(l && l->prog);
    const lin::LinearModel m = LinearizeAt(*l->prog, lin::StartPoint(*l->prog));
    // 6 chart coordinates less the height (normal row): 5; 6 speeds less 3 rolling rows: 3.
    EXPECT_EQ(m.n_coords, 5);
    EXPECT_EQ(m.states.size(), 8u);
    EXPECT_LT(m.unsteady, 1e-6) << "v = " << v;
    const double W = v / a, lam2 = (4 * kG / a - 12 * W * W) / 5;  // (5)
    const auto ev = NonZero(m, 1e-5);
    ASSERT_EQ(ev.size(), 2u) << "v = " << v;
    for (const auto& e : ev) {
      const std::complex<double> e2 = e * e;
      EXPECT_NEAR(e2.real(), lam2, 1e-7 * std::max(1.0, std::abs(lam2))) << "v = " << v;
      EXPECT_NEAR(e2.imag(), 0.0, 1e-7 * std::max(1.0, std::abs(lam2)));
    }
    const bool stable = v > vc;
    EXPECT_EQ(std::max(ev[0].real(), ev[1].real()) > 1e-6, !stable) << "v = " << v;
    // The ignorable coordinates: position on the ground, heading, spin.
    for (const char* name : {"px.q", "pz.q", "heading.q", "spin.q"})
      EXPECT_NE(std::find(m.ignorable.begin(), m.ignorable.end(), name), m.ignorable.end()) << name;
  }
}

const char* kSleepingTop = R"(
// A symmetric top on two tilt hinges and a spin hinge (the spin innermost, so the spin
// angle is ignorable); the pivot at the origin, the axis along world z, gravity -z.
model Top
  parameter Real m = 1.2;
  parameter Real l = 0.08;
  parameter Real A0 = 2e-3 "transverse central moment";
  parameter Real C = 3e-3 "axial moment";
  parameter Real s = 60 "spin";
  World world(g = {0, 0, -9.81});
  Revolute tilt1(axis = {1, 0, 0});
  Revolute tilt2(axis = {0, 1, 0});
  Revolute spin(axis = {0, 0, 1}, u(start = s));
  Body top(m = m, r_CM = {0, 0, l}, I = diagonal({A0, A0, C}));
equation
  connect(world.frame_b, tilt1.frame_a);
  connect(tilt1.frame_b, tilt2.frame_a);
  connect(tilt2.frame_b, spin.frame_a);
  connect(spin.frame_b, top.frame_a);
end Top;
)";

TEST(Linearize, SleepingTopStabilityLimit) {
  // If this fails, gyroscopic coupling is linearized wrongly: the sleeping top's
  // eigenvalues (6) on both sides of its stability limit s_c = 2 sqrt(A m g l) / C.
  const double m = 1.2, l = 0.08, A = 2e-3 + m * l * l, C = 3e-3;
  const double sc = 2 * std::sqrt(A * m * kG * l) / C;  // 27.2 rad/s
  for (double s : {0.5 * sc, 0.95 * sc, 1.05 * sc, 2.0 * sc}) {
    auto lt = LoadModel(kSleepingTop, {{"s", std::to_string(s)}}, {}, true);
    ASSERT_TRUE(lt && lt->prog);
    const lin::LinearModel md = LinearizeAt(*lt->prog, lin::StartPoint(*lt->prog));
    EXPECT_LT(md.unsteady, 1e-6);
    const auto ev = NonZero(md, 1e-6);
    ASSERT_EQ(ev.size(), 4u) << "s = " << s;
    const std::complex<double> disc = std::sqrt(std::complex<double>(C * C * s * s - 4 * A * m * kG * l));
    std::vector<std::complex<double>> want;
    for (double sign : {1.0, -1.0}) {
      const std::complex<double> lam = std::complex<double>(0, 1) * (C * s + sign * disc) / (2 * A);
      want.push_back(lam);
      want.push_back(std::conj(lam));
    }
    for (const auto& w : want) {
      double best = 1e300;
      for (const auto& e : ev) best = std::min(best, std::abs(e - w));
      EXPECT_LT(best, 1e-7 * std::abs(w)) << "s = " << s << " lambda " << w;
    }
    double rmax = -1;
    for (const auto& e : ev) rmax = std::max(rmax, e.real());
    EXPECT_EQ(rmax > 1e-6, s < sc) << "s = " << s;
  }
}

TEST(Linearize, SpinningQuaternionChartIsFlaggedUnsteady) {
  // If this fails, the frozen-instant linearization of examples/rolling_disk.mech (a
  // spinning free joint: its quaternion chart does not follow the spin) would be printed
  // as if its eigenvalues were stability exponents.
  auto l = LoadModel(kRoot + "/examples/rolling_disk.mech", {{"theta", "0"}, {"v_straight", "2"}});
  ASSERT_TRUE(l && l->prog);
  const lin::LinearModel m = LinearizeAt(*l->prog, lin::StartPoint(*l->prog));
  EXPECT_GT(m.unsteady, 1e-3);
}

TEST(Linearize, SmallDisturbanceFollowsTheLinearModelToSecondOrder) {
  // If this fails, A does not describe the nonlinear model's motion near the operating
  // point: the difference must shrink like the square of the disturbance.
  auto base = LoadModel(kDoublePendulum, {}, {}, true);
  ASSERT_TRUE(base && base->prog);
  const lin::LinearModel m = LinearizeAt(*base->prog, lin::StartPoint(*base->prog));
  const double T = 2.0;
  double err[2];
  for (int k = 0; k < 2; ++k) {
    const double eps = 0.02 / (1 << k);
    auto l = LoadModel(kDoublePendulum, {{"th1", "-pi/2+" + std::to_string(eps)}}, {}, true);
    ASSERT_TRUE(l && l->prog);
    auto s = RunModel(*l->prog, T, 0.05, 1e-12, {"shoulder.q", "elbow.q"});
    Eigen::VectorXd x0 = Eigen::VectorXd::Zero(4);
    x0[0] = eps;
    double e = 0.0;
    for (size_t i = 0; i < s.times.size(); ++i) {
      const Eigen::VectorXd x = (m.A * s.times[i]).exp() * x0;
      e = std::max(e, std::abs(s.rows[i][0] - (-M_PI / 2 + x[0])) + std::abs(s.rows[i][1] - x[1]));
    }
    err[k] = e;
  }
  // The linear model is right to first order, so the difference is of second order in
  // the disturbance at least; about the hanging double pendulum the nonlinearity is odd
  // (sin), so it is of third order: halving the disturbance divides it by 8 (a wrong A
  // would leave a first-order difference, a ratio of 2).
  EXPECT_GT(err[0] / err[1], 7.5) << err[0] << " " << err[1];
  EXPECT_LT(err[0] / err[1], 8.5) << err[0] << " " << err[1];
  EXPECT_LT(err[0], 0.02 * 0.02 * 10);
}

TEST(Linearize, AtATimeOfTheLoopedMotion) {
  // If this fails, the state of a run (integrated, then projected) is not a consistent
  // operating point, or the energy of the four-bar's motion is not kept to --at.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  lin::OperatingPoint op;
  const lin::Status s = lin::PointAtTime(*l->prog, 0.5, &op);
  ASSERT_TRUE(s.ok()) << s.message;
  EXPECT_DOUBLE_EQ(op.t, 0.5);
  const lin::LinearModel m = LinearizeAt(*l->prog, op);
  EXPECT_EQ(m.states.size(), 2u);
  EXPECT_GT(m.unsteady, 1e-6);  // a moving crank-rocker is no steady motion
  lin::OperatingPoint before;
  EXPECT_EQ(lin::PointAtTime(*l->prog, -1.0, &before).code, 1);
}

TEST(Linearize, FourBarSmallDisturbanceFollowsTheLinearModelToSecondOrder) {
  // If this fails, the looped linear model (one coordinate left by the loop) does not
  // describe the nonlinear four-bar near its equilibrium: the difference must shrink
  // like the square of the disturbance (the potential is not symmetric about it).
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  lin::EquilibriumResult eq;
  ASSERT_TRUE(lin::FindEquilibrium(*l->prog, lin::StartPoint(*l->prog), &eq).ok());
  const lin::LinearModel m = LinearizeAt(*l->prog, eq.point);
  ASSERT_EQ(m.states.front(), "crank_pivot.q");
  const double th = eq.point.y[static_cast<size_t>(FreeQ(*l->prog, "crank_pivot"))];
  double err[2];
  for (int k = 0; k < 2; ++k) {
    const double eps = 0.01 / (1 << k);
    char th0[64];
    std::snprintf(th0, sizeof th0, "%.17g", th + eps);
    auto lk = LoadModel(kRoot + "/examples/fourbar.mech", {{"theta0", th0}, {"omega0", "0"}});
    ASSERT_TRUE(lk && lk->prog);
    auto s = RunModel(*lk->prog, 1.5, 0.05, 1e-11, {"crank_pivot.q"});
    double e = 0.0;
    for (size_t i = 0; i < s.times.size(); ++i) {
      const Eigen::Vector2d x = (m.A * s.times[i]).exp() * Eigen::Vector2d(eps, 0);
      e = std::max(e, std::abs(s.rows[i][0] - th - x[0]));
    }
    err[k] = e;
  }
  EXPECT_GT(err[0] / err[1], 3.5) << err[0] << " " << err[1];
  EXPECT_LT(err[0] / err[1], 4.5) << err[0] << " " << err[1];
}

TEST(Linearize, UprightDiskReducedAndMultiplierFormsAgree) {
  // If this fails, the rolling rows' linear model depends on how the equations are solved.
  rt::CompileOptions dense, sparse;
  dense.solver = rt::SolverPath::Dense;
  sparse.solver = rt::SolverPath::Sparse;
  auto ld = LoadModel(kRoot + "/examples/rolling_disk_upright.mech", {}, dense);
  auto ls = LoadModel(kRoot + "/examples/rolling_disk_upright.mech", {}, sparse);
  ASSERT_TRUE(ld && ld->prog && ls && ls->prog);
  ASSERT_EQ(ls->prog->solver, rt::SolverPath::Sparse);
  const lin::LinearModel md = LinearizeAt(*ld->prog, lin::StartPoint(*ld->prog));
  const lin::LinearModel ms = LinearizeAt(*ls->prog, lin::StartPoint(*ls->prog));
  ASSERT_EQ(md.states, ms.states);
  EXPECT_LT((md.A - ms.A).cwiseAbs().maxCoeff(), 1e-8 * std::max(1.0, md.A.cwiseAbs().maxCoeff()));
}

TEST(Linearize, OperatingPointOffTheLoopIsRefused) {
  // If this fails, a state that does not close the loop is linearized as if it did.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  lin::OperatingPoint op = lin::StartPoint(*l->prog);
  op.y[static_cast<size_t>(FreeQ(*l->prog, "rocker_pivot"))] += 0.05;
  lin::LinearModel m;
  const lin::Status s = lin::Linearize(*l->prog, op, {}, &m);
  EXPECT_EQ(s.code, 1);
  EXPECT_NE(s.message.find("violates the position constraint loop 'coupler_rocker'"), std::string::npos) << s.message;
  EXPECT_NE(s.where.file.str().find("fourbar.mech"), std::string::npos);  // the cut joint's declaration
  EXPECT_EQ(s.where.line, 25);
}

TEST(Linearize, SingularConfigurationIsRefused) {
  // If this fails, a parallelogram linkage folded flat (the constraint Jacobian loses
  // rank) gets a linear model that is not valid there.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech", {{"a", "0.3"}, {"c", "0.3"}, {"theta0", "0.5"}});
  ASSERT_TRUE(l && l->prog);
  lin::OperatingPoint op = lin::StartPoint(*l->prog);
  for (const char* j : {"crank_pivot", "crank_coupler", "rocker_pivot"}) op.y[static_cast<size_t>(FreeQ(*l->prog, j))] = 0.0;
  for (int i = 0; i < l->prog->nu; ++i) op.y[static_cast<size_t>(l->prog->nq + i)] = 0.0;
  lin::LinearModel m;
  const lin::Status s = lin::Linearize(*l->prog, op, {}, &m);
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.message.find("singular configuration"), std::string::npos) << s.message;
}

TEST(Linearize, UnknownInputIsABadInput) {
  // If this fails, a misspelt input is silently ignored.
  auto l = LoadModel(kPendulum);
  ASSERT_TRUE(l && l->prog);
  lin::LinearizeOptions o;
  o.inputs = {"hinge.torque"};
  lin::LinearModel m;
  const lin::Status s = lin::Linearize(*l->prog, lin::StartPoint(*l->prog), o, &m);
  EXPECT_EQ(s.code, 1);
  EXPECT_NE(s.message.find("neither a joint's generalized force"), std::string::npos) << s.message;
  o.inputs = {"hinge.tau[2]"};
  EXPECT_EQ(lin::Linearize(*l->prog, lin::StartPoint(*l->prog), o, &m).code, 1);
  o.inputs.clear();
  o.outputs = {"hinge.qq"};
  EXPECT_EQ(lin::Linearize(*l->prog, lin::StartPoint(*l->prog), o, &m).code, 1);
}

}  // namespace
}  // namespace kanesim::test
