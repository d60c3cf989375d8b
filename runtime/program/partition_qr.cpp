// rt::PartitionQR: Eigen's ColPivHouseholderQR::computeInPlace (Eigen 3.4) step by step, on
// a profile of the non-zero rows of each column (runtime/program/partition_qr.h).
#include "runtime/program/partition_qr.h"

#include <algorithm>
#include <Eigen/Householder>
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

// A vector's sum (squaredNorm, dot): Eigen's redux, LinearVectorizedTraversal, for `size`
// terms given at increasing offsets (the others zero). Two packet accumulators over blocks of
// four terms, added, then a last whole packet, the two lanes added, then the last odd term.
class ReduxSum {
 public:
  explicit ReduxSum(Eigen::Index size) : end4_(size / 4 * 4), end2_(size / 2 * 2) {}
  void Add(Eigen::Index o, double t) {
    if (o < end4_) {
      switch (o & 3) {
        case 0: a0_ += t; break;
        case 1: a1_ += t; break;
        case 2: b0_ += t; break;
        default: b1_ += t; break;
      }
    } else if (o < end2_) {
      Combine();
      ((o & 1) ? a1_ : a0_) += t;
    } else {
      Finish();
      r_ += t;
    }
  }
  double Result() {
    Finish();
    return r_;
  }

 private:
  void Combine() {
    if (phase_ > 0) return;
    a0_ += b0_;
    a1_ += b1_;
    phase_ = 1;
  }
  void Finish() {
    Combine();
    if (phase_ > 1) return;
    r_ = a0_ + a1_;
    phase_ = 2;
  }
  Eigen::Index end4_, end2_;
  double a0_ = 0.0, a1_ = 0.0, b0_ = 0.0, b1_ = 0.0, r_ = 0.0;
  int phase_ = 0;
};

// One entry of a row vector times a matrix (Eigen's row-major general_matrix_vector_product:
// the reflector's v^T times a column): one packet accumulator over pairs of terms, its lanes
// added, then the last odd term.
class GemvSum {
 public:
  explicit GemvSum(Eigen::Index size) : end2_(size / 2 * 2) {}
  void Add(Eigen::Index o, double t) {
    if (o < end2_) {
      ((o & 1) ? l1_ : l0_) += t;
      return;
    }
    Finish();
    r_ += t;
  }
  double Result() {
    Finish();
    return r_;
  }

 private:
  void Finish() {
    if (done_) return;
    r_ = l0_ + l1_;
    done_ = true;
  }
  Eigen::Index end2_;
  double l0_ = 0.0, l1_ = 0.0, r_ = 0.0;
  bool done_ = false;
};

// Calls f(i) for the rows i >= first set in both bit sets a and b (b null: a alone), in
// increasing order.
template <class F>
void ForRows(const uint64_t* a, const uint64_t* b, Eigen::Index words, Eigen::Index first, F f) {
  for (Eigen::Index w = first / 64; w < words; ++w) {
    uint64_t bits = a[w] & (b ? b[w] : ~uint64_t{0});
    if (w == first / 64) bits &= ~uint64_t{0} << (first % 64);
    while (bits) {
      f(w * 64 + __builtin_ctzll(bits));
      bits &= bits - 1;
    }
  }
}

// sum of a[i]^2 over the rows first <= i < m of the set `rows` (Eigen: col.tail(m - first)
// .squaredNorm()).
double SquaredNorm(const double* a, const uint64_t* rows, Eigen::Index words, Eigen::Index first, Eigen::Index m) {
  ReduxSum s(m - first);
  ForRows(rows, nullptr, words, first, [&](Eigen::Index i) { s.Add(i - first, a[i] * a[i]); });
  return s.Result();
}

}  // namespace

void PartitionQR::Resize(Eigen::Index m, Eigen::Index n) {
  qr_.setZero(m, n);
  norm_upd_.setZero(n);
  norm_dir_.setZero(n);
  perm_.assign(static_cast<size_t>(n), 0);
  words_ = (m + 63) / 64;
  rows_.assign(static_cast<size_t>(n * words_), 0);
  vrows_.assign(static_cast<size_t>(words_), 0);
  v_.assign(static_cast<size_t>(m), 0.0);
  temp_.setZero(n);
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

// Step k from the pivot's swap on, as Eigen's computeInPlace, with Eigen's own calls.
void PartitionQR::DenseStep(Eigen::Index k) {
  const Eigen::Index m = qr_.rows(), n = qr_.cols();
  double tau = 0.0, beta = 0.0;
  qr_.col(k).tail(m - k).makeHouseholderInPlace(tau, beta);
  qr_(k, k) = beta;
  if (std::fabs(beta) > max_pivot_) max_pivot_ = std::fabs(beta);
  qr_.bottomRightCorner(m - k, n - k - 1).applyHouseholderOnTheLeft(qr_.col(k).tail(m - k - 1), tau, &temp_(k + 1));
  const double downdate_threshold = std::sqrt(std::numeric_limits<double>::epsilon());
  for (Eigen::Index j = k + 1; j < n; ++j) {
    if (norm_upd_[j] == 0.0) continue;
    double t = std::fabs(qr_(k, j)) / norm_upd_[j];
    t = (1.0 + t) * (1.0 - t);
    t = t < 0.0 ? 0.0 : t;
    const double ratio = norm_upd_[j] / norm_dir_[j];
    if (t * (ratio * ratio) <= downdate_threshold) {
      norm_dir_[j] = norm_upd_[j] = qr_.col(j).tail(m - k - 1).norm();
    } else {
      norm_upd_[j] *= std::sqrt(t);
    }
  }
}

void PartitionQR::Compute(const Eigen::MatrixXd& A, Eigen::Index steps) {
  qr_ = A;  // same size: no allocation
  const Eigen::Index m = qr_.rows(), n = qr_.cols(), size = std::min(m, n), W = words_;
  steps_ = steps < 0 ? size : std::min(steps, size);
  uint64_t* vrows = vrows_.data();
  const auto rows = [&](Eigen::Index j) { return rows_.data() + j * W; };
  // Column norms (Eigen: m_colNormsDirect = m_colNormsUpdated = col.norm()), and each
  // column's non-zero rows.
  double max_norm = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    const double* a = &qr_(0, j);
    uint64_t* r = rows(j);
    std::fill(r, r + W, uint64_t{0});
    for (Eigen::Index i = 0; i < m; ++i)
      if (a[i] != 0.0) r[i / 64] |= uint64_t{1} << (i % 64);
    norm_dir_[j] = norm_upd_[j] = std::sqrt(SquaredNorm(a, r, W, 0, m));
    max_norm = std::max(max_norm, norm_upd_[j]);  // Eigen's maxCoeff: the same value
    perm_[static_cast<size_t>(j)] = static_cast<int>(j);
  }
  const double eps = std::numeric_limits<double>::epsilon();
  const double threshold_helper = (max_norm * eps) * (max_norm * eps) / static_cast<double>(m);
  const double downdate_threshold = std::sqrt(eps);
  nonzero_pivots_ = size;
  max_pivot_ = 0.0;
  bool dense = false;

  for (Eigen::Index k = 0; k < steps_; ++k) {
    // The largest remaining norm; the first of equal ones (Eigen's maxCoeff: strict >).
    Eigen::Index best = k;
    for (Eigen::Index j = k + 1; j < n; ++j)
      if (norm_upd_[j] > norm_upd_[best]) best = j;
    const double best_sq = norm_upd_[best] * norm_upd_[best];
    if (nonzero_pivots_ == size && best_sq < threshold_helper * static_cast<double>(m - k)) nonzero_pivots_ = k;
    if (best != k) {
      qr_.col(k).swap(qr_.col(best));
      std::swap_ranges(rows(k), rows(k) + W, rows(best));
      std::swap(norm_upd_[k], norm_upd_[best]);
      std::swap(norm_dir_[k], norm_dir_[best]);
      std::swap(perm_[static_cast<size_t>(k)], perm_[static_cast<size_t>(best)]);
    }
    if (!dense) {
      // Sparse while the reflector's rows are few: with the pivots jumping along a chain, the
      // trailing block fills in (the chain of 40 at its change points: after ~20 of 80
      // steps); from there on Eigen's own steps on the dense block, which are faster there.
      Eigen::Index count = 1;
      ForRows(rows(k), nullptr, W, k + 1, [&](Eigen::Index) { ++count; });
      dense = 4 * count > m - k;
    }
    if (dense) {
      DenseStep(k);
      continue;
    }
    // The reflector of row k and the pivot column's rows below it (Eigen's
    // makeHouseholderInPlace of col(k).tail(m - k)).
    double* c = &qr_(0, k);
    const double tail_sq = m - k == 1 ? 0.0 : SquaredNorm(c, rows(k), W, k + 1, m);
    const double c0 = c[k];
    double tau = 0.0, beta = c0;
    if (tail_sq <= std::numeric_limits<double>::min()) {
      ForRows(rows(k), nullptr, W, k + 1, [&](Eigen::Index i) { c[i] = 0.0; });
    } else {
      beta = std::sqrt(c0 * c0 + tail_sq);
      if (c0 >= 0.0) beta = -beta;
      const double d = c0 - beta;
      ForRows(rows(k), nullptr, W, k + 1, [&](Eigen::Index i) { c[i] = c[i] / d; });
      tau = (beta - c0) / beta;
    }
    c[k] = beta;
    if (std::fabs(beta) > max_pivot_) max_pivot_ = std::fabs(beta);
    // Rows of the reflector: k and the pivot column's below k.
    std::fill(vrows, vrows + W, uint64_t{0});
    ForRows(rows(k), nullptr, W, k + 1, [&](Eigen::Index i) { vrows[i / 64] |= uint64_t{1} << (i % 64); });
    vrows[k / 64] |= uint64_t{1} << (k % 64);
    const bool apply = tau != 0.0 && m - k > 1;  // Eigen: rows() == 1 scales by 1 - tau = 1
    if (apply) ForRows(vrows, nullptr, W, k + 1, [&](Eigen::Index i) { v_[static_cast<size_t>(i)] = tau * c[i]; });
    // Apply it to the columns with a row among the reflector's (Eigen: tmp = v^T bottom +
    // row 0, row 0 -= tau tmp, bottom -= (tau v) tmp); the others are unchanged, and so are
    // their norms (R(k, j) = 0 downdates by a factor 1).
    for (Eigen::Index j = k + 1; j < n; ++j) {
      uint64_t* r = rows(j);
      bool meets = false;
      for (Eigen::Index w = k / 64; w < W && !meets; ++w) meets = (r[w] & vrows[w]) != 0;
      if (!meets) continue;
      double* a = &qr_(0, j);
      if (apply) {
        // Eigen takes a dot product (its redux order) when the block left has one column,
        // its matrix-vector kernel otherwise; the terms are v_i a_i over rows k + 1 ...
        double w;
        if (n - k - 1 == 1) {
          ReduxSum s(m - k - 1);
          ForRows(r, vrows, W, k + 1, [&](Eigen::Index i) { s.Add(i - k - 1, c[i] * a[i]); });
          w = s.Result();
        } else {
          GemvSum s(m - k - 1);
          ForRows(r, vrows, W, k + 1, [&](Eigen::Index i) { s.Add(i - k - 1, c[i] * a[i]); });
          w = s.Result();
        }
        w += a[k];
        a[k] -= tau * w;
        ForRows(vrows, nullptr, W, k + 1, [&](Eigen::Index i) { a[i] -= w * v_[static_cast<size_t>(i)]; });
        for (Eigen::Index x = 0; x < W; ++x) r[x] |= vrows[x];
      }
      // Norm downdate (LAWN 176, as Eigen and LAPACK's xGEQPF).
      if (norm_upd_[j] != 0.0) {
        double t = std::fabs(a[k]) / norm_upd_[j];
        t = (1.0 + t) * (1.0 - t);
        t = t < 0.0 ? 0.0 : t;
        const double ratio = norm_upd_[j] / norm_dir_[j];
        if (t * (ratio * ratio) <= downdate_threshold) {
          norm_dir_[j] = norm_upd_[j] = std::sqrt(SquaredNorm(a, r, W, k + 1, m));
        } else {
          norm_upd_[j] *= std::sqrt(t);
        }
      }
    }
  }
}

}  // namespace kanesim::rt
