// rt::SmallQR (runtime/program/small_qr.h) against the definition: Q R reproduces A, Q is
// orthogonal, R is upper triangular, and the least-squares solve agrees with Eigen's
// HouseholderQR, on random tall and square matrices, with a zero column thrown in.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <algorithm>
#include <random>
#include <vector>

#include "runtime/program/small_qr.h"

namespace kanesim::rt {
namespace {

TEST(SmallQR, FactorsAndSolvesLikeTheDefinition) {
  // If this fails, a Householder reflector or the stored vectors are wrong, and the
  // closed loops' dependent speeds with them.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int m = 1; m <= 7; ++m)
    for (int n = 1; n <= m; ++n) {
      Eigen::MatrixXd A(m, n);
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < n; ++j) A(i, j) = U(rng);
      if (m == 5 && n == 3) A.col(0).tail(m - 1).setZero();  // a column already triangular
      SmallQR qr;
      qr.Resize(m, n);
      qr.Compute(A);
      // Q^T A = R: upper triangular, and Q Q^T = I.
      Eigen::MatrixXd QtA(m, n), Q(m, m);
      for (int j = 0; j < n; ++j) {
        Eigen::VectorXd c = A.col(j);
        qr.ApplyQt(&c);
        QtA.col(j) = c;
      }
      for (int j = 0; j < m; ++j) {
        Eigen::VectorXd e = Eigen::VectorXd::Unit(m, j);
        qr.ApplyQ(&e);
        Q.col(j) = e;
      }
      EXPECT_LT((Q.transpose() * Q - Eigen::MatrixXd::Identity(m, m)).norm(), 1e-14) << m << "x" << n;
      for (int j = 0; j < n; ++j)
        for (int i = j + 1; i < m; ++i) EXPECT_NEAR(QtA(i, j), 0.0, 1e-14) << m << "x" << n;
      for (int k = 0; k < n; ++k) EXPECT_NEAR(std::fabs(QtA(k, k)), qr.DiagAbs(k), 1e-14);
      // Least squares: x = R^-1 (Q^T b)(0:n), and R^-T against R.
      Eigen::VectorXd b(m);
      for (int i = 0; i < m; ++i) b[i] = U(rng);
      Eigen::VectorXd x = b;
      qr.ApplyQt(&x);
      qr.SolveR(x.data());
      const Eigen::VectorXd ref = A.householderQr().solve(b);
      EXPECT_LT((x.head(n) - ref).norm(), 1e-12 * (1.0 + ref.norm())) << m << "x" << n;
      Eigen::VectorXd y = ref;
      const Eigen::MatrixXd R = QtA.topRows(n).triangularView<Eigen::Upper>();
      Eigen::VectorXd rty = R.transpose() * y;
      qr.SolveRt(rty.data());
      EXPECT_LT((rty - y).norm(), 1e-12 * (1.0 + y.norm())) << m << "x" << n;
    }
}

// Q^T A = R (upper triangular), Q orthogonal, |R_kk| as Eigen's HouseholderQR's, and the
// solves against Eigen's: the checks of FactorsAndSolvesLikeTheDefinition for one matrix.
void ExpectFactorsLikeEigen(const Eigen::MatrixXd& A, const char* what) {
  const auto m = A.rows(), n = A.cols();
  SmallQR qr;
  qr.Resize(m, n);
  qr.Compute(A);
  Eigen::MatrixXd QtA(m, n), Q(m, m);
  for (Eigen::Index j = 0; j < n; ++j) {
    Eigen::VectorXd c = A.col(j);
    qr.ApplyQt(&c);
    QtA.col(j) = c;
  }
  for (Eigen::Index j = 0; j < m; ++j) {
    Eigen::VectorXd e = Eigen::VectorXd::Unit(m, j);
    qr.ApplyQ(&e);
    Q.col(j) = e;
  }
  const double scale = A.norm();
  EXPECT_LT((Q.transpose() * Q - Eigen::MatrixXd::Identity(m, m)).norm(), 1e-13) << what;
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = j + 1; i < m; ++i) EXPECT_NEAR(QtA(i, j), 0.0, 1e-14 * scale) << what << " " << i << "," << j;
  const Eigen::HouseholderQR<Eigen::MatrixXd> ref_qr(A);
  for (Eigen::Index k = 0; k < n; ++k) {
    EXPECT_NEAR(std::fabs(QtA(k, k)), qr.DiagAbs(k), 1e-13 * scale) << what;
    EXPECT_NEAR(std::fabs(ref_qr.matrixQR()(k, k)), qr.DiagAbs(k), 1e-12 * scale) << what << " k=" << k;
  }
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m, -1.0, 2.0);
  Eigen::VectorXd x = b;
  qr.ApplyQt(&x);
  qr.SolveR(x.data());
  const Eigen::VectorXd ref = ref_qr.solve(b);
  EXPECT_LT((x.head(n) - ref).norm(), 1e-10 * (1.0 + ref.norm())) << what;
  const Eigen::MatrixXd R = QtA.topRows(n).triangularView<Eigen::Upper>();
  Eigen::VectorXd rty = R.transpose() * ref;
  qr.SolveRt(rty.data());
  EXPECT_LT((rty - ref).norm(), 1e-10 * (1.0 + ref.norm())) << what;
}

TEST(SmallQR, SparsePatternsFactorLikeTheDenseAlgorithm) {
  // If this fails, the profile QR skipped a non-zero (a column or reflector extent, or
  // R's row ends, kept wrong), and a chain of loops' dependent speeds with it
  // (constraints.cpp BandedOrder: block-banded A_dep from 16 dependent speeds on).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::bernoulli_distribution keep(0.3);
  // A chain of 40 planar loops: 2 rows per loop, loop i moved by rod i - 1, coupler i and
  // rod i; columns in the banded order (coupler i, rod i), then shuffled (the pivoting
  // order: the profile then spreads, and the result must still be exact).
  const int loops = 40, m = 2 * loops, n = 2 * loops;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, n);
  for (int i = 0; i < loops; ++i)
    for (int r = 2 * i; r < 2 * i + 2; ++r) {
      A(r, 2 * i) = U(rng);      // coupler i
      A(r, 2 * i + 1) = U(rng);  // rod i
      if (i > 0) A(r, 2 * i - 1) = U(rng);  // rod i - 1
    }
  ExpectFactorsLikeEigen(A, "banded chain");
  std::vector<int> perm(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) perm[static_cast<size_t>(j)] = j;
  std::shuffle(perm.begin(), perm.end(), rng);
  Eigen::MatrixXd P(m, n);
  for (int j = 0; j < n; ++j) P.col(j) = A.col(perm[static_cast<size_t>(j)]);
  ExpectFactorsLikeEigen(P, "shuffled chain");
  // Tall matrices with scattered zeros, leading and trailing zero runs per column, and a
  // column that is zero below its diagonal.
  for (int trial = 0; trial < 20; ++trial) {
    const int rows = 6 + trial % 9, cols = 3 + trial % 4;
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(rows, cols);
    for (int j = 0; j < cols; ++j) {
      S(j, j) = 0.5 + 0.5 * std::fabs(U(rng));  // full column rank
      for (int i = 0; i < rows; ++i)
        if (keep(rng)) S(i, j) = U(rng);
    }
    if (trial % 5 == 0) S.col(cols - 1).tail(rows - cols).setZero();
    ExpectFactorsLikeEigen(S, "scattered");
  }
}

}  // namespace
}  // namespace kanesim::rt
