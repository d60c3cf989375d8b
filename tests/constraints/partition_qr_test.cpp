// rt::PartitionQR (runtime/program/partition_qr.h) against Eigen's ColPivHouseholderQR,
// whose choice it must reproduce (the closed loops' speed partition, docs/constraints.md
// "Several loops singular at once"): the same pivot columns, the same |R(k, k)|, the same
// rank and non-zero pivots, on random dense, random banded (a chain's profile), rank-deficient
// and tied matrices, and on the Jacobian of the chain of 40 parallelograms at states through
// its change points.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "runtime/constraints/constraints.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/partition_qr.h"
#include "runtime/runtime.h"
#include "runtime/program/program.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

// Pivots of Eigen's factorization and ours agree for the first `steps` columns, and |R(k,k)|
// to the bit. Returns the number of agreeing pivots (steps when all agree).
int ComparePivots(const Eigen::MatrixXd& A, Eigen::Index steps, const std::string& what, bool full = true) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> ref(A);
  rt::PartitionQR qr;
  qr.Resize(A.rows(), A.cols());
  qr.Compute(A, full ? -1 : steps);
  const auto& perm = ref.colsPermutation().indices();
  for (Eigen::Index k = 0; k < steps; ++k) {
    EXPECT_EQ(qr.Indices()[static_cast<size_t>(k)], perm[k]) << what << ": pivot " << k;
    if (qr.Indices()[static_cast<size_t>(k)] != perm[k]) return static_cast<int>(k);
    // Bit for bit: the same operations in the same order as Eigen's.
    EXPECT_EQ(qr.DiagAbs(k), std::fabs(ref.matrixQR()(k, k))) << what << ": |R(k,k)| at " << k;
  }
  if (full) {
    EXPECT_EQ(qr.Rank(), ref.rank()) << what;
    EXPECT_EQ(qr.NonzeroPivots(), ref.nonzeroPivots()) << what;
  }
  return static_cast<int>(steps);
}

TEST(PartitionQR, PivotsAsEigenOnRandomDenseMatrices) {
  // If this fails, the pivoting rule (largest remaining norm, first of equal ones), the
  // norm downdate or the reflectors differ from Eigen's.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int m = 1; m <= 12; ++m)
    for (int n = 1; n <= 14; ++n) {
      Eigen::MatrixXd A(m, n);
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < n; ++j) A(i, j) = U(rng);
      ComparePivots(A, std::min(m, n), "dense " + std::to_string(m) + "x" + std::to_string(n));
    }
  Eigen::MatrixXd A = Eigen::MatrixXd::Random(40, 41);
  ComparePivots(A, 40, "dense 40x41");
}

TEST(PartitionQR, PivotsAsEigenOnBandedMatrices) {
  // A chain's profile: column j non-zero in a few rows around 2 j / 2 (+ scale spread so
  // the norm ordering is not the index ordering). Fails if a skipped column or row were not
  // an exact zero, or if the profile's fill were tracked wrong.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0), S(0.1, 10.0);
  for (int trial = 0; trial < 40; ++trial) {
    const int m = 2 * (5 + trial), n = m + 1 + trial % 3, bw = 2 + trial % 4;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, n);
    for (int j = 0; j < n; ++j) {
      const int c = j * m / n, s = S(rng) > 5.0 ? 1 : 0;
      for (int i = std::max(0, c - bw / 2); i < std::min(m, c + bw); ++i) A(i, j) = U(rng) * (s ? 3.0 : 1.0);
    }
    ComparePivots(A, std::min(m, n), "banded " + std::to_string(trial));
  }
}

TEST(PartitionQR, PivotsAndRankAsEigenOnRankDeficientMatrices) {
  // Rank r < min(m, n): columns that are combinations of others, exact zero columns. The
  // rank decision (|R(k,k)| against eps min(m,n) max pivot) and the pivots up to it agree.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    const int m = 6 + trial % 7, n = m + 2, r = 2 + trial % (m - 2);
    Eigen::MatrixXd L(m, r), R(r, n);
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < r; ++j) L(i, j) = U(rng);
    for (int i = 0; i < r; ++i)
      for (int j = 0; j < n; ++j) R(i, j) = U(rng);
    Eigen::MatrixXd A = L * R;
    A.col(trial % n).setZero();
    rt::PartitionQR qr;
    qr.Resize(m, n);
    qr.Compute(A);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> ref(A);
    EXPECT_EQ(qr.Rank(), ref.rank()) << trial;
    EXPECT_LE(qr.Rank(), r) << trial;
    ComparePivots(A, ref.rank(), "rank deficient " + std::to_string(trial));
  }
}

TEST(PartitionQR, TiesGoToTheFirstColumnAsInEigen) {
  // Equal columns (equal links make equal norms): Eigen takes the first of the largest.
  // Fails if the choice took the last, or compared with >=.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6, 7);
  for (int j = 0; j < 7; ++j) {
    A(j % 6, j) = 1.0;
    A((j + 1) % 6, j) = 0.5;
  }
  ComparePivots(A, 6, "tied");
  // A pivot order that is not the identity: the largest column last.
  A(2, 6) = 3.0;
  rt::PartitionQR qr;
  qr.Resize(6, 7);
  qr.Compute(A);
  EXPECT_EQ(qr.Indices()[0], 6);
  ComparePivots(A, 6, "tied, largest last");
}

TEST(PartitionQR, StopsAfterTheStepsAskedWithTheSamePivots) {
  // Compute(A, steps) stops early; its first pivots are the full factorization's.
  Eigen::MatrixXd A = Eigen::MatrixXd::Random(20, 23);
  ComparePivots(A, 12, "first 12 of 20x23", /*full=*/false);
}

// The chain of 40 equal-link parallelograms (tests/stress/models/parallelogram_chain.mech):
// the Jacobian of its 80 active rows on its 81 free speeds after the projection, at rod
// angles through the change points (theta = k pi: every loop singular at once) and away from
// them, with the rods at exactly the same angle (ties) and a little apart (an integrator's
// noise).
TEST(PartitionQR, PivotsAsEigenOnTheChainOfFortyJacobian) {
  auto l = LoadModel(kRoot + "/tests/stress/models/parallelogram_chain.mech", {{"N", "40"}});
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), yd(y.size());
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const double pi = std::acos(-1.0);
  int compared = 0;
  for (double base : {-0.5, 0.0, pi, 1.0})
    for (double off : {0.3, 1e-2, 1e-3, 1e-4, -1e-4, -1e-3})
      for (double noise : {0.0, 1e-12, 1e-9}) {
        rt::InitialState(p, y.data());
        const double th = base + off;
        for (const auto& j : p.joints) {
          const auto q = static_cast<size_t>(j.q0);
          const bool rod = j.name.rfind("rj", 0) == 0, cpl = j.name.rfind("cj", 0) == 0;
          if (rod) y[q] = th + noise * U(rng);
          if (cpl) y[q] = -th + noise * U(rng);
          if (rod || cpl) y[static_cast<size_t>(p.nq + j.u0)] = (rod ? 12.0 : -12.0) * (1.0 + noise * U(rng));
        }
        if (rt::Derivative(p, *ws, 0.0, y.data(), yd.data()) != 0) continue;  // refused as singular
        ASSERT_EQ(ws->A.rows(), 80);
        ASSERT_EQ(ws->A.cols(), 81);
        ComparePivots(ws->A, p.loop_rank,
                      "chain of 40 at theta " + std::to_string(th) + ", noise " + std::to_string(noise));
        ++compared;
      }
  EXPECT_GE(compared, 40);  // most states compared, not refused
}

// ConstraintJacobian zeroes only the entries the Jacobians write (constraints.cpp
// ZeroJacobian), not all of A: on a workspace that has evaluated the chain of 40 at other
// states before (its A full of old values), A at a new state is bit for bit the one a fresh
// workspace computes there. Fails if an entry written were left out of the zeroed pattern
// (it would keep the sum of two states' values).
TEST(PartitionQR, JacobianOnAUsedWorkspaceAsOnAFreshOne) {
  auto l = LoadModel(kRoot + "/tests/stress/models/parallelogram_chain.mech", {{"N", "40"}});
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto used = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), yd(y.size());
  const auto set_angle = [&](double th) {
    rt::InitialState(p, y.data());
    for (const auto& j : p.joints) {
      const auto q = static_cast<size_t>(j.q0);
      if (j.name.rfind("rj", 0) == 0) y[q] = th;
      if (j.name.rfind("cj", 0) == 0) y[q] = -th;
    }
  };
  for (double th : {-0.5, 0.4, 1.3, 2.2}) {
    set_angle(th);
    ASSERT_EQ(rt::Derivative(p, *used, 0.0, y.data(), yd.data()), 0) << th;
  }
  ASSERT_GT(used->A.cwiseAbs().sum(), 0.0);
  set_angle(2.9);
  auto fresh = rt::MakeWorkspace(p);
  for (auto* ws : {used.get(), fresh.get()}) {
    ASSERT_EQ(rt::UnpackState(p, *ws, 0.0, y.data()), 0);
    rt::PositionKinematics(p, *ws);
    rt::VelocityKinematics(p, *ws);
    rt::ConstraintJacobian(p, *ws);
  }
  EXPECT_GT(fresh->A.cwiseAbs().maxCoeff(), 0.1);
  for (Eigen::Index j = 0; j < fresh->A.cols(); ++j)
    for (Eigen::Index i = 0; i < fresh->A.rows(); ++i) ASSERT_EQ(used->A(i, j), fresh->A(i, j)) << i << "," << j;
}

}  // namespace
}  // namespace kanesim::test
