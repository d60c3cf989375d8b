// Lesser's diagonal speeds (sim/diagonal_speeds.h, issue 44): the mass matrix they factor
// against the scene's own solve, the factors against a dense Cholesky, Lesser's own
// two-degree-of-freedom example (1992 §6, eqs. 77-92) in his formulas, the motion against the
// joint speeds' and the energy split T = 1/2 sum d_i w_i^2 against the kinetic energy.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <string>
#include <vector>

#include "runtime/program/program.h"
#include "runtime/runtime.h"
#include "sim/diagonal_speeds.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

const std::string kLesser = kRoot + "/tests/sim/models/lesser_fig1.mech";

// A branched tree with a quaternion joint and a prismatic one: M depends on all of them.
const char* kTree = R"(model Tree
  World world(g = {0, -9.81, 0});
  Revolute a(axis = {0, 0, 1}, q(start = 0.4), u(start = 0.7));
  Rod r1(L = 0.8, m = 1.5);
  Spherical ball(q(start = {0.8, 0.36, 0.48, 0}), u(start = {0.5, -0.3, 0.9}));
  Body b2(m = 0.9, r_CM = {0.3, 0.05, 0}, I = diagonal({0.02, 0.03, 0.04}));
  FixedTranslation t2(r = {0.6, 0, 0});
  Prismatic slide(axis = {0, 1, 0}, q(start = 0.2), u(start = 0.1));
  Rod r3(L = 0.5, m = 0.7);
  Revolute b(axis = {0, 1, 0}, q(start = -0.3), u(start = 0.2));
  Rod r4(L = 0.5, m = 0.4);
equation
  connect(world.frame_b, a.frame_a);
  connect(a.frame_b, r1.frame_a);
  connect(r1.frame_b, ball.frame_a);
  connect(ball.frame_b, b2.frame_a);
  connect(ball.frame_b, t2.frame_a);
  connect(t2.frame_b, slide.frame_a);
  connect(slide.frame_b, r3.frame_a);
  connect(r1.frame_b, b.frame_a);
  connect(b.frame_b, r4.frame_a);
end Tree;)";

// A prescribed (rheonomic) joint between two free ones: M depends on time, and Mdot on dM/dt.
const char* kDriven = R"(model Driven
  World world(g = {0, -9.81, 0});
  Revolute j1(axis = {0, 0, 1}, q(start = 0.3), u(start = 0.5));
  Rod r1(L = 0.7, m = 1.2);
  Revolute p(axis = {1, 0, 0});
  Revolute j2(axis = {0, 0, 1}, q(start = -0.4), u(start = 0.1));
  Rod r2(L = 0.5, m = 0.8);
equation
  connect(world.frame_b, j1.frame_a);
  connect(j1.frame_b, r1.frame_a);
  connect(r1.frame_b, p.frame_a);
  connect(p.frame_b, j2.frame_a);
  connect(j2.frame_b, r2.frame_a);
  p.q = 0.8 * sin(3 * time);
end Driven;)";

// Round-off of an n <= 8 factorization of a matrix with entries O(1): far below 1e-12.
constexpr double kFactorTol = 1e-12;

Eigen::MatrixXd MassAt(const rt::Program& p, const std::vector<double>& y, double t = 0.0) {
  auto ws = rt::MakeWorkspace(p);
  Eigen::MatrixXd M(p.nu, p.nu);
  EXPECT_EQ(rt::MassMatrix(p, *ws, t, y.data(), M.data()), 0) << rt::ErrorMessage(*ws);
  return M;
}

std::vector<double> StartState(const rt::Program& p) {
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p)));
  rt::InitialState(p, y.data());
  return y;
}

// The scene's own solve (recursive or dense) gives M^-1 columns: M M^-1 = 1.
TEST(DiagonalSpeeds, MassMatrixInvertsTheScenesSolve) {
  for (rt::SolverPath path : {rt::SolverPath::Dense, rt::SolverPath::Recursive}) {
    rt::CompileOptions o;
    o.solver = path;
    auto m = LoadModel(kTree, {}, o, true);
    const rt::Program& p = *m->prog;
    const std::vector<double> y = StartState(p);
    const Eigen::MatrixXd M = MassAt(p, y);
    auto ws = rt::MakeWorkspace(p);
    Eigen::MatrixXd Minv(p.nu, p.nu);
    for (int k = 0; k < p.nu; ++k) ASSERT_EQ(rt::InverseMassColumn(p, *ws, 0.0, y.data(), k, Minv.col(k).data()), 0);
    EXPECT_LT((M * Minv - Eigen::MatrixXd::Identity(p.nu, p.nu)).cwiseAbs().maxCoeff(), kFactorTol)
        << "path " << static_cast<int>(path);
  }
}

// L D L^T in the order against Eigen's unpivoted Cholesky LL^T of the permuted M:
// d_i = Lc_ii^2, L_ij = Lc_ij / Lc_jj.
void ExpectFactorsOfCholesky(const Eigen::MatrixXd& M, const std::vector<int>& order) {
  const int n = static_cast<int>(order.size());
  Eigen::MatrixXd Mp(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) Mp(a, b) = M(order[static_cast<size_t>(a)], order[static_cast<size_t>(b)]);
  Eigen::LLT<Eigen::MatrixXd> llt(Mp);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Eigen::MatrixXd Lc = llt.matrixL();
  sim::DiagonalFactor f(order);
  ASSERT_EQ(f.Factor(M.data()), 0);
  for (int j = 0; j < n; ++j) {
    const double dj = Lc(j, j) * Lc(j, j);
    EXPECT_NEAR(f.d()(j), dj, kFactorTol * dj) << "d[" << j + 1 << "]";
    for (int i = j + 1; i < n; ++i) EXPECT_NEAR(f.L()(i, j), Lc(i, j) / Lc(j, j), kFactorTol) << i << "," << j;
  }
  // w = L^T u and back, and T = 1/2 u^T M u = 1/2 sum d_i w_i^2 for an arbitrary u.
  Eigen::VectorXd u(n), w(n), u2(n);
  for (int i = 0; i < n; ++i) u(i) = std::sin(1.3 * i + 0.2);
  f.SpeedsToW(u.data(), w.data());
  f.WToSpeeds(w.data(), u2.data());
  EXPECT_LT((u2 - u).cwiseAbs().maxCoeff(), kFactorTol);
  const double T = 0.5 * u.dot(M * u), Tw = 0.5 * (f.d().array() * w.array().square()).sum();
  EXPECT_NEAR(Tw, T, kFactorTol * T);
}

TEST(DiagonalSpeeds, FactorsEqualADenseCholeskyOfM) {
  auto m = LoadModel(kTree, {}, {}, true);
  const rt::Program& p = *m->prog;
  std::vector<double> y = StartState(p);
  const Eigen::MatrixXd M = MassAt(p, y);
  std::string error;
  ExpectFactorsOfCholesky(M, sim::SpeedOrder(p, {}, &error));           // root to leaf
  ExpectFactorsOfCholesky(M, sim::SpeedOrder(p, {"b", "slide"}, &error));  // the user's order first
  const std::vector<std::string> names = sim::FreeSpeedNames(p);
  const std::vector<int> order = sim::SpeedOrder(p, {"b", "slide"}, &error);
  EXPECT_EQ(names[static_cast<size_t>(order[0])], "b.u");
  EXPECT_EQ(names[static_cast<size_t>(order[1])], "slide.u");
  EXPECT_EQ(names[static_cast<size_t>(order[2])], "a.u") << "the others root to leaf";
  EXPECT_TRUE(sim::SpeedOrder(p, {"nope"}, &error).empty());
  EXPECT_NE(error.find("no joint named 'nope'"), std::string::npos) << error;
}

// Lesser's figure 1 with his speeds u1 = q1', u2 = q2' (q2 absolute): the tangent vectors of
// eqs. (77)-(78), tau1 = {2l b2, n}, {l b2, 0} and tau2 = {0, 0}, {s c2, n}, in the kinetic
// metric (point mass M1 at Q: no inertia; body M2, I at C) give
//   |tau1|^2 = 4 l^2 M1 + l^2 M2,  tau1.tau2 = M2 l s cos(q2 - q1),  |tau2|^2 = M2 s^2 + I,
// then eqs. (84)-(85) a1 = |tau1|, a2 = tau2 . tau1 / a1, (83) tau2' = tau2 - a2 tau1/a1 with
// |tau2'|^2 = |tau2|^2 - a2^2, and (91)-(92) w1 = a1 u1 + a2 u2, w2 = u2.
TEST(DiagonalSpeeds, LesserTwoDofExampleInHisFormulas) {
  auto m = LoadModel(kLesser);
  const rt::Program& p = *m->prog;
  const double l = 0.7, s = 0.4, M1 = 1.3, M2 = 2.1, I = 0.35;  // the model's parameters
  for (double hinge : {1.1, 0.0, -2.4}) {
    std::vector<double> y = StartState(p);
    y[1] = hinge;  // [pivot.q, hinge.q, pivot.u, hinge.u]
    const double q1 = y[0], q2 = y[0] + y[1];
    Eigen::Matrix2d ML;
    ML << 4 * l * l * M1 + l * l * M2, M2 * l * s * std::cos(q2 - q1), M2 * l * s * std::cos(q2 - q1), M2 * s * s + I;
    // kanesim's speeds are the joints' (hinge relative): u_K = [u1, u2 - u1] = S^-1 u_L.
    Eigen::Matrix2d S;
    S << 1, 0, 1, 1;  // u_L = S u_K
    const Eigen::MatrixXd MK = MassAt(p, y);
    EXPECT_LT((MK - S.transpose() * ML * S).cwiseAbs().maxCoeff(), kFactorTol) << "the model is Lesser's figure 1";

    const Eigen::Matrix2d MLs = (S.inverse().transpose() * MK * S.inverse());  // M in Lesser's speeds, from kanesim's M
    sim::DiagonalFactor f({0, 1});
    ASSERT_EQ(f.Factor(MLs.data()), 0);
    const double a1 = std::sqrt(ML(0, 0)), a2 = ML(0, 1) / a1;          // (84), (85)
    EXPECT_NEAR(f.d()(0), a1 * a1, kFactorTol);                           // tau1 normalized by a1
    EXPECT_NEAR(f.d()(1), ML(1, 1) - a2 * a2, kFactorTol);               // |tau2'|^2 (83)
    const double u1 = 0.8, u2 = -0.5;
    double u[2] = {u1, u2}, w[2];
    f.SpeedsToW(u, w);
    EXPECT_NEAR(a1 * w[0], a1 * u1 + a2 * u2, kFactorTol);  // (91): Lesser's w1 = sqrt(d1) w1
    EXPECT_NEAR(w[1], u2, kFactorTol);                       // (92)
  }
}

// Integrated in w, the motion is the joint speeds' to the tolerance's reach.
struct Case {
  std::string model;
  bool is_text;
  std::vector<lang::ParamOverride> sets;
  std::vector<std::string> order;
};

sim::MemorySink RunWith(const rt::Program& p, sim::Speeds speeds, const std::vector<std::string>& order,
                    const std::vector<std::string>& signals) {
  sim::SimOptions o;
  o.stop_time = 2.0;
  o.interval = 0.1;
  o.rtol = o.atol = 1e-11;
  o.signals = signals;
  o.speeds = speeds;
  o.speed_order = order;
  sim::MemorySink sink;
  sim::SimResult r = sim::Simulate(p, o, sink);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  return sink;
}

// rtol 1e-11 over 2 s: the two runs are different ODEs, each within ~1e-9 of the motion.
constexpr double kMotionTol = 1e-7;

TEST(DiagonalSpeeds, MotionEqualsTheJointSpeeds) {
  const std::vector<Case> cases = {
      {kRoot + "/examples/double_pendulum.mech", false, {}, {}},
      {kRoot + "/examples/chain.mech", false, {{"N", "5"}}, {}},
      {kRoot + "/examples/chain.mech", false, {{"N", "5"}}, {"j[5]", "j[2]"}},
      {kTree, true, {}, {}},
      {kDriven, true, {}, {}},
      {kLesser, false, {}, {"hinge"}},
  };
  for (const Case& c : cases) {
    auto m = LoadModel(c.model, c.sets, {}, c.is_text);
    const rt::Program& p = *m->prog;
    const std::vector<std::string> signals = rt::DefaultSignals(p);
    sim::MemorySink a = RunWith(p, sim::Speeds::kJoint, {}, signals);
    sim::MemorySink b = RunWith(p, sim::Speeds::kDiagonal, c.order, signals);
    ASSERT_EQ(a.rows.size(), b.rows.size()) << c.model;
    ASSERT_EQ(b.names.size(), signals.size() + 3 * static_cast<size_t>(p.nu)) << "w, d and T_w per speed";
    double worst = 0.0;
    for (size_t r = 0; r < a.rows.size(); ++r)
      for (size_t k = 0; k < signals.size(); ++k) worst = std::max(worst, std::abs(a.rows[r][k] - b.rows[r][k]));
    EXPECT_LT(worst, kMotionTol) << c.model;
    EXPECT_GT(worst, 0.0) << c.model << ": the same numbers twice would mean w was not integrated";
  }
}

TEST(DiagonalSpeeds, EnergySplitIsTheKineticEnergy) {
  for (const std::string& model : {kRoot + "/examples/chain.mech", std::string(kTree)}) {
    auto m = LoadModel(model, {}, {}, model == kTree);
    const rt::Program& p = *m->prog;
    sim::MemorySink b = RunWith(p, sim::Speeds::kDiagonal, {}, {"kinetic_energy"});
    const size_t n = static_cast<size_t>(p.nu);
    for (const std::vector<double>& row : b.rows) {
      double sum = 0.0;
      for (size_t i = 0; i < n; ++i) {
        const double w = row[1 + i], d = row[1 + n + i], e = row[1 + 2 * n + i];
        EXPECT_NEAR(e, 0.5 * d * w * w, 1e-15 * (1 + e));
        EXPECT_GT(d, 0.0);
        sum += e;
      }
      EXPECT_NEAR(sum, row[0], kFactorTol * (1 + row[0]));
    }
  }
}

// Closed loops on the multiplier form have no partition into independent speeds.
TEST(DiagonalSpeeds, MultiplierFormIsRefusedInWords) {
  rt::CompileOptions sparse;
  sparse.solver = rt::SolverPath::Sparse;
  auto m = LoadModel(kRoot + "/examples/fourbar.mech", {}, sparse);
  sim::MemorySink sink;
  sim::SimOptions o;
  o.speeds = sim::Speeds::kDiagonal;
  sim::SimResult r = sim::Simulate(*m->prog, o, sink);
  EXPECT_EQ(r.status, sim::SimResult::Status::kUsageError);
  EXPECT_NE(r.message.find("multiplier form"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace kanesim::test
