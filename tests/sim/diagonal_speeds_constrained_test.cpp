// Lesser's diagonal speeds on closed loops and rolling contacts (sim/diagonal_speeds.h,
// ConstrainedBasis; issue 44 §1): the motion against the joint speeds' on the four-bar and the
// rolling disk, and D against a dense LDL^T (Cholesky) of beta^T M beta, with M the mass matrix
// of the same bodies and joints as a tree (the loop cut open, the contact taken away): an M
// from the mass-matrix path, not from the kinetic energy the basis polarizes.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/program/program.h"
#include "runtime/runtime.h"
#include "sim/diagonal_speeds.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

const std::string kFourBar = kRoot + "/examples/fourbar.mech";
const std::string kDisk = kRoot + "/examples/rolling_disk.mech";

// The model's text without the lines that mention `drop` (the cut joint, the contact).
std::string Without(const std::string& path, const std::string& drop) {
  std::ifstream in(path);
  std::ostringstream out;
  for (std::string line; std::getline(in, line);)
    if (line.find(drop) == std::string::npos) out << line << "\n";
  return out.str();
}

// D of the basis' M~ (polarized kinetic energy) against the squared diagonal of a Cholesky
// factor of beta^T M_tree beta at the state y (its coordinates projected by the basis).
void ExpectDEqualsDenseLdlt(const rt::Program& loop, const rt::Program& tree, std::vector<double> y) {
  ASSERT_EQ(sim::FreeSpeedNames(loop), sim::FreeSpeedNames(tree));
  ASSERT_EQ(rt::StateSize(loop), rt::StateSize(tree));
  sim::ConstrainedBasis basis(loop);
  std::string error;
  ASSERT_EQ(basis.Init(0.0, y.data(), &error), 0) << error;
  const int m = static_cast<int>(basis.Independent().size()), nq = loop.nq, nu = loop.nu;
  ASSERT_EQ(m, sim::DiagonalSpeedCount(loop));
  Eigen::MatrixXd beta(nu, m);
  std::vector<double> x(static_cast<size_t>(m)), z(y.size());
  for (int i = 0; i < m; ++i) {
    std::fill(x.begin(), x.end(), 0.0);
    x[static_cast<size_t>(i)] = 1.0;
    ASSERT_EQ(basis.Complete(0.0, y.data(), x.data(), z.data()), 0) << basis.Error();
    for (int r = 0; r < nu; ++r) beta(r, i) = z[static_cast<size_t>(nq + r)];
  }
  auto ws = rt::MakeWorkspace(tree);
  Eigen::MatrixXd M(nu, nu);
  ASSERT_EQ(rt::MassMatrix(tree, *ws, 0.0, z.data(), M.data()), 0) << rt::ErrorMessage(*ws);
  const Eigen::MatrixXd reduced = beta.transpose() * M * beta;
  Eigen::MatrixXd polarized(m, m);
  ASSERT_EQ(basis.ReducedMass(0.0, y.data(), polarized.data()), 0) << basis.Error();
  std::vector<int> order(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) order[static_cast<size_t>(i)] = i;
  sim::DiagonalFactor f(order);
  ASSERT_EQ(f.Factor(polarized.data()), 0);
  const Eigen::MatrixXd Lc = Eigen::LLT<Eigen::MatrixXd>(reduced).matrixL();
  const double scale = reduced.diagonal().maxCoeff();
  for (int i = 0; i < m; ++i) {
    EXPECT_NEAR(f.d()(i), Lc(i, i) * Lc(i, i), 1e-12 * scale) << "d[" << i + 1 << "]";
    for (int j = 0; j < i; ++j) EXPECT_NEAR(f.L()(i, j), Lc(i, j) / Lc(j, j), 1e-11) << "L(" << i << "," << j << ")";
  }
}

std::vector<double> Start(const rt::Program& p) {
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p)));
  rt::InitialState(p, y.data());
  return y;
}

TEST(DiagonalSpeedsConstrained, FourBarDEqualsADenseLdltOfTheReducedMassMatrix) {
  auto loop = LoadModel(kFourBar);
  auto tree = LoadModel(Without(kFourBar, "coupler_rocker"), {}, {}, true);
  ASSERT_TRUE(loop && loop->prog && tree && tree->prog);
  std::vector<double> y = Start(*loop->prog);
  ExpectDEqualsDenseLdlt(*loop->prog, *tree->prog, y);
  y[0] += 1.0;  // another crank angle (the basis' projection closes the loop there)
  ExpectDEqualsDenseLdlt(*loop->prog, *tree->prog, y);
}

TEST(DiagonalSpeedsConstrained, RollingDiskDEqualsADenseLdltOfTheReducedMassMatrix) {
  auto loop = LoadModel(kDisk);
  auto tree = LoadModel(Without(kDisk, "contact"), {}, {}, true);
  ASSERT_TRUE(loop && loop->prog && tree && tree->prog);
  ASSERT_EQ(sim::DiagonalSpeedCount(*loop->prog), 3);
  std::vector<double> y = Start(*loop->prog);
  ExpectDEqualsDenseLdlt(*loop->prog, *tree->prog, y);
}

sim::MemorySink RunWith(const rt::Program& p, sim::Speeds speeds, const std::vector<std::string>& signals, double stop) {
  sim::SimOptions o;
  o.stop_time = stop;
  o.interval = 0.1;
  o.rtol = o.atol = 1e-10;
  o.signals = signals;
  o.speeds = speeds;
  sim::MemorySink sink;
  sim::SimResult r = sim::Simulate(p, o, sink);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  return sink;
}

// rtol 1e-10: two different ODEs, each within ~1e-8 of the motion.
TEST(DiagonalSpeedsConstrained, MotionEqualsTheJointSpeeds) {
  for (const std::string& model : {kFourBar, kDisk}) {
    auto m = LoadModel(model, model == kDisk ? std::vector<lang::ParamOverride>{{"lean_rate", "0.1"}}
                                             : std::vector<lang::ParamOverride>{});
    const rt::Program& p = *m->prog;
    std::vector<std::string> signals = rt::DefaultSignals(p);
    signals.push_back("kinetic_energy");
    sim::MemorySink a = RunWith(p, sim::Speeds::kJoint, signals, 1.0);
    sim::MemorySink b = RunWith(p, sim::Speeds::kDiagonal, signals, 1.0);
    ASSERT_EQ(a.rows.size(), b.rows.size()) << model;
    const size_t n = static_cast<size_t>(sim::DiagonalSpeedCount(p));
    ASSERT_EQ(b.names.size(), signals.size() + 3 * n) << "w, d and T_w per independent speed";
    double worst = 0.0;
    for (size_t r = 0; r < a.rows.size(); ++r) {
      for (size_t k = 0; k < signals.size(); ++k) worst = std::max(worst, std::abs(a.rows[r][k] - b.rows[r][k]));
      double sum = 0.0;  // T = 1/2 sum d_i w_i^2 on the constrained basis too
      for (size_t i = 0; i < n; ++i) sum += b.rows[r][signals.size() + 2 * n + i];
      EXPECT_NEAR(sum, b.rows[r][signals.size() - 1], 1e-10 * (1 + sum)) << model << " row " << r;
    }
    EXPECT_LT(worst, 1e-7) << model;
    EXPECT_GT(worst, 0.0) << model << ": the same numbers twice would mean w was not integrated";
  }
}

}  // namespace
}  // namespace kanesim::test
