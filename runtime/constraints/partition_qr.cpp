// rt::PartitionQR: Eigen's ColPivHouseholderQR::computeInPlace (Eigen 3.4) step by step, on
// a profile of the non-zero rows of each column (runtime/constraints/partition_qr.h).
#include "runtime/constraints/partition_qr.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kanesim::rt {
namespace {

// Eigen 3.4 sums in a fixed order that depends on the position of each term, not on its value;
// so do these (with Eigen's SSE2 packets of two doubles and no fused multiply-add), and a
// term outside [o0, o1) is an exact zero that would add nothing. The choice then sees the
// very numbers Eigen's does, and ties (equal links: equal norms) fall the same way.
static_assert(Eigen::internal::packet_traits<double>::size == 2,
              "PartitionQR follows Eigen's summation order for packets of two doubles (SSE2)");

// A vector's sum (squaredNorm, dot): Eigen's redux, LinearVectorizedTraversal. Two packet
// accumulators over blocks of four terms, added, then a last whole packet, the two lanes
// added, then the last odd term. `size` terms, offsets o0 <= o < o1 possibly non-zero.
template <class Term>
double ReduxSum(Eigen::Index size, Eigen::Index o0, Eigen::Index o1, Term term) {
  const Eigen::Index end4 = size / 4 * 4, end2 = size / 2 * 2;
  double a0 = 0.0, a1 = 0.0, b0 = 0.0, b1 = 0.0;
  Eigen::Index o = o0;
  for (; o < std::min(o1, end4); ++o) {
    const double t = term(o);
    switch (o & 3) {
      case 0: a0 += t; break;
      case 1: a1 += t; break;
      case 2: b0 += t; break;
      default: b1 += t; break;
    }
  }
  a0 += b0;
  a1 += b1;
  for (; o < std::min(o1, end2); ++o) ((o & 1) ? a1 : a0) += term(o);
  double r = a0 + a1;
  for (; o < o1; ++o) r += term(o);
  return r;
}

// One entry of a row vector times a matrix (Eigen's row-major general_matrix_vector_product,
// the reflector's v^T times a column): one packet accumulator over pairs of terms, its lanes
// added, then the last odd term.
template <class Term>
double GemvSum(Eigen::Index size, Eigen::Index o0, Eigen::Index o1, Term term) {
  const Eigen::Index end2 = size / 2 * 2;
  double l0 = 0.0, l1 = 0.0;
  Eigen::Index o = o0;
  for (; o < std::min(o1, end2); ++o) ((o & 1) ? l1 : l0) += term(o);
  double r = l0 + l1;
  for (; o < o1; ++o) r += term(o);
  return r;
}

// sum of a[i]^2 for i in [first, last), the terms non-zero only in [lo, hi).
double SquaredNorm(const double* a, Eigen::Index first, Eigen::Index last, Eigen::Index lo, Eigen::Index hi) {
  const Eigen::Index o0 = std::max(lo, first) - first, o1 = std::max(o0, std::min(hi, last) - first);
  return ReduxSum(last - first, o0, o1, [&](Eigen::Index o) { return a[first + o] * a[first + o]; });
}

}  // namespace

void PartitionQR::Resize(Eigen::Index m, Eigen::Index n) {
  qr_.setZero(m, n);
  norm_upd_.setZero(n);
  norm_dir_.setZero(n);
  perm_.assign(static_cast<size_t>(n), 0);
  lo_.assign(static_cast<size_t>(n), 0);
  hi_.assign(static_cast<size_t>(n), 0);
  v_.assign(static_cast<size_t>(m), 0.0);
  steps_ = nonzero_pivots_ = 0;
  max_pivot_ = 0.0;
}

double PartitionQR::DiagAbs(Eigen::Index k) const { return std::fabs(qr_(k, k)); }

Eigen::Index PartitionQR::Rank() const {
  const double threshold = std::fabs(max_pivot_) * std::numeric_limits<double>::epsilon() *
                           static_cast<double>(std::min(qr_.rows(), qr_.cols()));
  Eigen::Index r = 0;
  for (Eigen::Index i = 0; i < nonzero_pivots_; ++i) r += std::fabs(qr_(i, i)) > threshold ? 1 : 0;
  return r;
}

void PartitionQR::Compute(const Eigen::MatrixXd& A, Eigen::Index steps) {
  qr_ = A;  // same size: no allocation
  const Eigen::Index m = qr_.rows(), n = qr_.cols(), size = std::min(m, n);
  steps_ = steps < 0 ? size : std::min(steps, size);
  const auto at = [](auto& vec, Eigen::Index i) -> auto& { return vec[static_cast<size_t>(i)]; };
  // Column norms (Eigen: m_colNormsDirect = m_colNormsUpdated = col.norm()), and each
  // column's non-zero rows.
  double max_norm = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    const double* a = &qr_(0, j);
    Eigen::Index lo = 0, hi = m;
    while (lo < m && a[lo] == 0.0) ++lo;
    while (hi > lo && a[hi - 1] == 0.0) --hi;
    at(lo_, j) = lo;
    at(hi_, j) = hi;
    norm_dir_[j] = norm_upd_[j] = std::sqrt(SquaredNorm(a, 0, m, lo, hi));
    max_norm = std::max(max_norm, norm_upd_[j]);  // Eigen's maxCoeff: the same value
    perm_[static_cast<size_t>(j)] = static_cast<int>(j);
  }
  const double eps = std::numeric_limits<double>::epsilon();
  const double threshold_helper = (max_norm * eps) * (max_norm * eps) / static_cast<double>(m);
  const double downdate_threshold = std::sqrt(eps);
  nonzero_pivots_ = size;
  max_pivot_ = 0.0;

  for (Eigen::Index k = 0; k < steps_; ++k) {
    // The largest remaining norm; the first of equal ones (Eigen's maxCoeff: strict >).
    Eigen::Index best = k;
    for (Eigen::Index j = k + 1; j < n; ++j)
      if (norm_upd_[j] > norm_upd_[best]) best = j;
    const double best_sq = norm_upd_[best] * norm_upd_[best];
    if (nonzero_pivots_ == size && best_sq < threshold_helper * static_cast<double>(m - k)) nonzero_pivots_ = k;
    if (best != k) {
      const Eigen::Index r0 = std::min(at(lo_, k), at(lo_, best)), r1 = std::max(at(hi_, k), at(hi_, best));
      for (Eigen::Index i = r0; i < r1; ++i) std::swap(qr_(i, k), qr_(i, best));
      std::swap(at(lo_, k), at(lo_, best));
      std::swap(at(hi_, k), at(hi_, best));
      std::swap(norm_upd_[k], norm_upd_[best]);
      std::swap(norm_dir_[k], norm_dir_[best]);
      std::swap(at(perm_, k), at(perm_, best));
    }
    // The reflector of rows k <= i < end (Eigen's makeHouseholderInPlace).
    double* c = &qr_(0, k);
    const Eigen::Index end = std::max(at(hi_, k), k + 1);
    const double tail_sq = m - k == 1 ? 0.0 : SquaredNorm(c, k + 1, m, at(lo_, k), end);
    const double c0 = c[k];
    double tau = 0.0, beta = c0;
    if (tail_sq <= std::numeric_limits<double>::min()) {
      for (Eigen::Index i = k + 1; i < end; ++i) c[i] = 0.0;
    } else {
      beta = std::sqrt(c0 * c0 + tail_sq);
      if (c0 >= 0.0) beta = -beta;
      const double d = c0 - beta;
      for (Eigen::Index i = k + 1; i < end; ++i) c[i] = c[i] / d;
      tau = (beta - c0) / beta;
    }
    c[k] = beta;
    if (std::fabs(beta) > max_pivot_) max_pivot_ = std::fabs(beta);
    // Apply it to the columns whose rows overlap k..end (Eigen: tmp = v^T bottom + row 0,
    // row 0 -= tau tmp, bottom -= (tau v) tmp); the others are unchanged, and so are their
    // norms (R(k, j) = 0 downdates by a factor 1).
    if (tau != 0.0 && m - k > 1)
      for (Eigen::Index i = k + 1; i < end; ++i) v_[static_cast<size_t>(i)] = tau * c[i];
    for (Eigen::Index j = k + 1; j < n; ++j) {
      const Eigen::Index lo = std::max(at(lo_, j), k), hi = at(hi_, j);
      if (lo >= end || hi <= lo) continue;  // no overlap: nothing moves
      double* a = &qr_(0, j);
      if (tau != 0.0 && m - k > 1) {
        // Rows k + 1 <= i < end of v and of the column; Eigen takes a dot product (its redux
        // order) when the block left has one column, its matrix-vector kernel otherwise.
        const Eigen::Index len = m - k - 1, o0 = std::max(lo, k + 1) - (k + 1), o1 = std::min(hi, end) - (k + 1);
        const auto term = [&](Eigen::Index o) { return c[k + 1 + o] * a[k + 1 + o]; };
        double w = o1 <= o0 ? 0.0 : (n - k - 1 == 1 ? ReduxSum(len, o0, o1, term) : GemvSum(len, o0, o1, term));
        w += a[k];
        a[k] -= tau * w;
        for (Eigen::Index i = k + 1; i < end; ++i) a[i] -= w * v_[static_cast<size_t>(i)];
        at(lo_, j) = std::min(at(lo_, j), k);
        at(hi_, j) = std::max(hi, end);
      }
      // Norm downdate (LAWN 176, as Eigen and LAPACK's xGEQPF).
      if (norm_upd_[j] != 0.0) {
        double t = std::fabs(a[k]) / norm_upd_[j];
        t = (1.0 + t) * (1.0 - t);
        t = t < 0.0 ? 0.0 : t;
        const double ratio = norm_upd_[j] / norm_dir_[j];
        if (t * (ratio * ratio) <= downdate_threshold) {
          norm_dir_[j] = norm_upd_[j] = std::sqrt(SquaredNorm(a, k + 1, m, at(lo_, j), at(hi_, j)));
        } else {
          norm_upd_[j] *= std::sqrt(t);
        }
      }
    }
  }
}

}  // namespace kanesim::rt
