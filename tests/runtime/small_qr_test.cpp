// rt::SmallQR (runtime/program/small_qr.h) against the definition: Q R reproduces A, Q is
// orthogonal, R is upper triangular, and the least-squares solve agrees with Eigen's
// HouseholderQR, on random tall and square matrices, with a zero column thrown in.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <random>

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

}  // namespace
}  // namespace kanesim::rt
