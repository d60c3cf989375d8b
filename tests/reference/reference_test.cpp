// The examples, run end to end, against independent references:
// - examples/double_pendulum.mech against Lagrange's equations integrated in 40-digit
//   arithmetic (tests/data/double_pendulum_ref.csv, bench/reference/double_pendulum.py);
// - examples/chain.mech (N = 5, 20) against Pinocchio's ABA + DOP853 at 1e-13
//   (tests/data/chain*_ref.csv, bench/reference/chain_pinocchio.py);
// - a torque-free asymmetric body: energy and world angular momentum are invariants,
//   and rotation about the intermediate axis is unstable (it flips).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "tests/support/load_util.h"

namespace kanesim {
namespace {

struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<double>> rows;  // time first
  int Col(const std::string& n) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == n) return static_cast<int>(i);
    return -1;
  }
};

Table ReadCsv(const std::string& path) {
  Table t;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::stringstream hs(line);
  for (std::string c; std::getline(hs, c, ',');) t.names.push_back(c);
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::vector<double> r;
    for (std::string c; std::getline(ls, c, ',');) r.push_back(std::strtod(c.c_str(), nullptr));
    t.rows.push_back(r);
  }
  return t;
}

using test::kRoot;
using test::LoadModel;
using test::RunModel;

// A model given as text, compiled; fails the test on any error.
std::unique_ptr<test::Loaded> LoadText(const std::string& text, std::vector<lang::ParamOverride> sets = {}) {
  auto l = LoadModel(text, std::move(sets), {}, /*is_text=*/true);
  if (l && !l->errors.empty()) ADD_FAILURE() << l->errors[0].message;
  return l && l->prog ? std::move(l) : nullptr;
}

// Max |kanesim - reference| over the reference's rows with time <= t_max.
double MaxError(const sim::MemorySink& s, const Table& ref, const std::vector<std::string>& cols, double t_max) {
  double worst = 0;
  for (const auto& row : ref.rows) {
    double t = row[0];
    if (t > t_max + 1e-12) break;
    // Output grids coincide with the reference's times (same interval).
    size_t k = 0;
    while (k < s.times.size() && std::fabs(s.times[k] - t) > 1e-9) ++k;
    EXPECT_LT(k, s.times.size()) << "no output row at t = " << t;
    if (k == s.times.size()) return INFINITY;
    for (const auto& c : cols) {
      int ci = ref.Col(c);
      int si = -1;
      for (size_t i = 0; i < s.names.size(); ++i)
        if (s.names[i] == c) si = static_cast<int>(i);
      EXPECT_GE(ci, 0) << c;
      EXPECT_GE(si, 0) << c;
      if (ci < 0 || si < 0) return INFINITY;
      worst = std::max(worst, std::fabs(s.rows[k][static_cast<size_t>(si)] - row[static_cast<size_t>(ci)]));
    }
  }
  return worst;
}


// The double pendulum is chaotic: bench/reference/double_pendulum.md shows a double-
// precision solver can keep about 13 digits to t = 3 s (sigma_max ~ 1e3). With
// rtol = atol = 1e-12 the integrators measured 4e-9 (ARKODE: at 0.1 s output spacing its
// degree-5 dense output, not its steps, limits the error), 1e-8 (CVODE-Adams) and 9e-9
// (IDA) up to t = 3 s; the bounds leave a factor of about 10 to the measurements.
TEST(Reference, DoublePendulumAgainstLagrange40Digits) {
  auto l = LoadModel(kRoot + "/examples/double_pendulum.mech");
  ASSERT_TRUE(l);
  Table ref = ReadCsv(kRoot + "/tests/data/double_pendulum_ref.csv");
  std::vector<std::string> cols{"shoulder.q", "elbow.q", "shoulder.u", "elbow.u"};
  struct Case {
    rt::Integrator kind;
    double bound;
  };
  for (Case c : {Case{rt::Integrator::ArkodeErk, 5e-8}, Case{rt::Integrator::CvodeAdams, 1e-7},
                 Case{rt::Integrator::IDA, 1e-7}}) {
    auto s = RunModel(*l->prog, 3.0, 0.1, 1e-12, cols, c.kind);
    double err = MaxError(s, ref, cols, 3.0);
    EXPECT_LT(err, c.bound) << "integrator " << static_cast<int>(c.kind);
    RecordProperty("max_error_" + std::to_string(static_cast<int>(c.kind)), std::to_string(err));
  }
}

// examples/chain.mech against Pinocchio. The reference is good to ~1e-12 up to 3 s
// (bench/reference/chain_ref.md); we compare q up to 3 s at 1e-8 (rtol 1e-12, chaotic
// amplification ~1e3 by then) on both solution paths.
void CheckChain(int n) {
  std::string file = kRoot + "/tests/data/chain" + std::to_string(n) + "_ref.csv";
  Table ref = ReadCsv(file);
  std::vector<std::string> cols;
  for (int i = 1; i <= n; ++i) cols.push_back("j[" + std::to_string(i) + "].q");
  for (const char* path : {"dense", "sparse"}) {
    rt::CompileOptions co;
    co.solver = std::string(path) == "dense" ? rt::SolverPath::Dense : rt::SolverPath::Sparse;
    auto l = LoadModel(kRoot + "/examples/chain.mech", {{"N", std::to_string(n)}}, co);
    ASSERT_TRUE(l && l->prog);
    auto s = RunModel(*l->prog, 3.0, 0.05, 1e-12, cols, rt::Integrator::ArkodeErk);
    double err = MaxError(s, ref, cols, 3.0);
    EXPECT_LT(err, 1e-8) << "N = " << n << ", " << path;
  }
}

TEST(Reference, Chain5AgainstPinocchio) { CheckChain(5); }
TEST(Reference, Chain20AgainstPinocchio) { CheckChain(20); }

// A torque-free rigid body with principal inertias 1 < 2 < 3 spun about the
// intermediate axis: kinetic energy and the world-frame angular momentum must stay
// constant (no torque), and the spin must flip (Euler's equations: the intermediate
// axis is unstable), which here happens within 20 s for a 0.5 % perturbation.
TEST(Reference, TorqueFreeBodyConservesAndFlips) {
  const char* model = R"(
model Tumbling
  World world(g = {0, 0, 0});
  FreeMotion free(u(start = {0, 0, 0, 0.01, 2, 0.01}));
  Body b(m = 1, I = diagonal({1, 2, 3}));
equation
  connect(world.frame_b, free.frame_a);
  connect(free.frame_b, b.frame_a);
end Tumbling;
)";
  auto l = LoadText(model);
  ASSERT_TRUE(l);
  std::vector<std::string> sig{"kinetic_energy", "free.u[5]"};
  for (int i = 1; i <= 3; ++i) sig.push_back("b.w[" + std::to_string(i) + "]");
  for (int i = 1; i <= 3; ++i)
    for (int j = 1; j <= 3; ++j) sig.push_back("b.R[" + std::to_string(i) + "," + std::to_string(j) + "]");
  auto s = RunModel(*l->prog, 20.0, 0.01, 1e-10, sig);
  ASSERT_FALSE(s.rows.empty());
  const double I[3] = {1, 2, 3};
  auto momentum = [&](const std::vector<double>& r) {
    // H_W = R I R^T w_W, with w_W the angular velocity resolved in the world.
    double R[3][3], w[3], wb[3], h[3];
    for (int i = 0; i < 3; ++i) w[i] = r[static_cast<size_t>(2 + i)];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) R[i][j] = r[static_cast<size_t>(5 + 3 * i + j)];
    for (int j = 0; j < 3; ++j) wb[j] = R[0][j] * w[0] + R[1][j] * w[1] + R[2][j] * w[2];
    for (int i = 0; i < 3; ++i) h[i] = R[i][0] * I[0] * wb[0] + R[i][1] * I[1] * wb[1] + R[i][2] * I[2] * wb[2];
    return std::vector<double>{h[0], h[1], h[2]};
  };
  const double e0 = 0.5 * (1 * 0.01 * 0.01 + 2 * 4 + 3 * 0.01 * 0.01);
  std::vector<double> h0 = momentum(s.rows.front());
  EXPECT_NEAR(h0[1], 4.0, 1e-12);  // starts aligned with world y: 2 * 2
  double max_de = 0, max_dh = 0, min_wy = 1e9;
  for (const auto& r : s.rows) {
    max_de = std::max(max_de, std::fabs(r[0] - e0) / e0);
    auto h = momentum(r);
    for (int i = 0; i < 3; ++i) max_dh = std::max(max_dh, std::fabs(h[static_cast<size_t>(i)] - h0[static_cast<size_t>(i)]) / 4.0);
    min_wy = std::min(min_wy, r[1]);
  }
  // rtol 1e-10 over ~2000 steps: invariants hold to 1e-7 relative.
  EXPECT_LT(max_de, 1e-7);
  EXPECT_LT(max_dh, 1e-7);
  EXPECT_LT(min_wy, -1.9) << "the spin about the intermediate axis never flipped";
}

// A block on a rough incline, written with the stdlib's friction parameters: with
// mu < tan(alpha) it slides with a = g (sin(alpha) - mu cos(alpha)) (Coulomb, N = m g
// cos(alpha)); with mu > tan(alpha) it sticks (the tanh regularization lets it creep at
// most at the speed scale v).
TEST(Reference, BlockOnRoughInclineWrittenInTheLanguage) {
  const char* model = R"(
model Incline
  parameter Real alpha = 0.5;
  parameter Real mu = 0.2;
  World world(g = {0, -9.81, 0});
  Prismatic slide(axis = {cos(alpha), -sin(alpha), 0}, mu = mu, friction_v = 1e-3);
  Body cart(m = 2, I = identity(3) * 0.01);
equation
  connect(world.frame_b, slide.frame_a);
  connect(slide.frame_b, cart.frame_a);
end Incline;
)";
  for (double mu : {0.2, 0.8}) {
    auto l = LoadText(model, {{"mu", std::to_string(mu)}});
    ASSERT_TRUE(l);
    // Sticking makes the regularized law stiff (rate mu N / (m v) ~ 3e3 1/s): BDF.
    auto s = RunModel(*l->prog, 1.0, 0.5, 1e-10, {"slide.q", "slide.u"}, rt::Integrator::IDA);
    ASSERT_EQ(s.rows.size(), 3u);
    const double a = 9.81 * (std::sin(0.5) - mu * std::cos(0.5));
    if (a > 0) {
      // q(1) = a/2, plus what the regularization gives away while u ~ v at the start:
      // about (mu g cos(alpha)) (v / a) ln 2 * 1 s = 2e-4 m here.
      EXPECT_NEAR(s.rows.back()[0], 0.5 * a, 1e-3) << "mu = " << mu;
    } else {
      // Creep speed v atanh(tan(alpha) / mu) = 0.84 v at most.
      EXPECT_LT(std::fabs(s.rows.back()[1]), 1e-3) << "mu = " << mu << ": the block must stick";
    }
  }
}

}  // namespace
}  // namespace kanesim
