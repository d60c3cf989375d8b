// Householder QR of a small m x n matrix (m >= n) in plain loops, for the dependent block
// of closed loops (runtime/constraints/constraints.cpp): a few rows and columns per loop, factored
// twice per right-hand side. Eigen's dynamic-size HouseholderQR spends most of its time
// in block and expression set-up at these sizes (docs/benchmarks.md, the four-bar's
// profile).
//
// A = Q R with Q = H_0 H_1 ... H_{n-1}, H_k = I - tau_k v_k v_k^T, v_k(k) = 1 and its
// entries below the diagonal stored in column k under R (LAPACK's layout).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace kanesim::rt {

class SmallQR {
 public:
  void Resize(Eigen::Index m, Eigen::Index n) {
    qr_.setZero(m, n);
    tau_.setZero(n);
    inv_diag_.setZero(n);
    lo_.setZero(n);
    hi_.setZero(n);
    row_end_.setZero(n);
  }
  Eigen::Index Cols() const { return qr_.cols(); }
  double DiagAbs(Eigen::Index k) const { return std::fabs(qr_(k, k)); }

  // Profile (skyline) Householder: column j of the working matrix is non-zero only in rows
  // lo_(j) <= i < hi_(j), and reflector k only in rows k <= i < hi_(k) when it is made.
  // A step touches only the columns whose rows overlap the reflector's, and only those
  // rows; what it skips are exact zeros (a product with a zero factor, added or
  // subtracted), so the result is the plain dense algorithm's to the bit. A block-banded
  // A_dep (a chain of loops: loop i shares bodies with loops i +- 1) costs O(n bw^2)
  // instead of O(m n^2) (docs/benchmarks.md, "Change points").
  void Compute(const Eigen::MatrixXd& A) {
    qr_ = A;  // same size: no allocation
    const Eigen::Index m = qr_.rows(), n = qr_.cols();
    for (Eigen::Index j = 0; j < n; ++j) {
      const double* a = &qr_(0, j);
      Eigen::Index lo = 0, hi = m;
      while (lo < m && a[lo] == 0.0) ++lo;
      while (hi > lo && a[hi - 1] == 0.0) --hi;
      lo_[j] = lo;
      hi_[j] = hi;
    }
    for (Eigen::Index k = 0; k < n; ++k) {
      double* c = &qr_(0, k);
      const Eigen::Index end = std::max(hi_[k], k + 1);  // rows of reflector k: k <= i < end
      hi_[k] = end;
      double norm2 = 0.0;
      for (Eigen::Index i = k + 1; i < end; ++i) norm2 += c[i] * c[i];
      const double x0 = c[k];
      if (norm2 == 0.0) {  // already upper triangular in this column
        tau_[k] = 0.0;
        inv_diag_[k] = 1.0 / x0;
        continue;
      }
      const double alpha = x0 > 0.0 ? -std::sqrt(x0 * x0 + norm2) : std::sqrt(x0 * x0 + norm2);
      const double v0 = x0 - alpha;
      for (Eigen::Index i = k + 1; i < end; ++i) c[i] /= v0;  // v = [1; c(k+1:) / v0]
      tau_[k] = (alpha - x0) / alpha;
      c[k] = alpha;
      inv_diag_[k] = 1.0 / alpha;
      for (Eigen::Index j = k + 1; j < n; ++j) {  // H_k applied to the remaining columns
        if (std::max(lo_[j], k) >= std::min(hi_[j], end)) continue;  // no row in common
        double* a = &qr_(0, j);
        double s = a[k];
        for (Eigen::Index i = k + 1; i < end; ++i) s += c[i] * a[i];
        s *= tau_[k];
        a[k] -= s;
        for (Eigen::Index i = k + 1; i < end; ++i) a[i] -= s * c[i];
        lo_[j] = std::min(lo_[j], k);
        hi_[j] = std::max(hi_[j], end);
      }
    }
    // R's rows: row i is non-zero from the diagonal to column row_end_(i) - 1 (column j of
    // R starts at row lo_(j)).
    for (Eigen::Index i = 0; i < n; ++i) row_end_[i] = i + 1;
    for (Eigen::Index j = 0; j < n; ++j)
      for (Eigen::Index i = std::min(lo_[j], j); i < j; ++i) row_end_[i] = std::max(row_end_[i], j + 1);
  }

  // v <- Q^T v (v has m entries).
  void ApplyQt(Eigen::VectorXd* v) const {
    for (Eigen::Index k = 0; k < qr_.cols(); ++k) Reflect(k, v->data());
  }
  // v <- Q v.
  void ApplyQ(Eigen::VectorXd* v) const {
    for (Eigen::Index k = qr_.cols(); k-- > 0;) Reflect(k, v->data());
  }
  // x(0:n) <- R^-1 x(0:n).
  void SolveR(double* x) const {
    for (Eigen::Index i = qr_.cols(); i-- > 0;) {
      double s = x[i];
      for (Eigen::Index j = i + 1; j < row_end_[i]; ++j) s -= qr_(i, j) * x[j];
      x[i] = s * inv_diag_[i];
    }
  }
  // x(0:n) <- R^-T x(0:n).
  void SolveRt(double* x) const {
    for (Eigen::Index i = 0; i < qr_.cols(); ++i) {
      double s = x[i];
      for (Eigen::Index j = std::min(lo_[i], i); j < i; ++j) s -= qr_(j, i) * x[j];
      x[i] = s * inv_diag_[i];
    }
  }

 private:
  void Reflect(Eigen::Index k, double* v) const {
    const double* c = &qr_(0, k);
    if (tau_[k] == 0.0) return;  // H_k = I
    double s = v[k];
    for (Eigen::Index i = k + 1; i < hi_[k]; ++i) s += c[i] * v[i];
    s *= tau_[k];
    v[k] -= s;
    for (Eigen::Index i = k + 1; i < hi_[k]; ++i) v[i] -= s * c[i];
  }

  Eigen::MatrixXd qr_;
  Eigen::VectorXd tau_;
  Eigen::VectorXd inv_diag_;  // 1 / R_kk, so that the solves multiply (off the division's latency)
  // Profile of the factorization (Compute): column j of R starts at row lo_(j); reflector k
  // ends before row hi_(k); row i of R ends before column row_end_(i).  (n each)
  Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> lo_, hi_, row_end_;
};

}  // namespace kanesim::rt
