// sim/box_lcp.h: projected Gauss-Seidel for a first guess, then least-index principal pivoting.
#include "sim/box_lcp.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace kanesim::sim {

namespace {
constexpr int kGaussSeidelSweeps = 200;  // the guess only: pivoting makes it exact
}  // namespace

BoxLcpResult SolveBoxLcp(const std::vector<double>& A, const std::vector<double>& q, const std::vector<double>& lo,
                         const std::vector<double>& hi, double tol) {
  const size_t m = q.size();
  BoxLcpResult r;
  r.x.assign(m, 0.0);
  r.w = q;
  r.state.assign(m, BoxState::kFree);
  if (A.size() != m * m || lo.size() != m || hi.size() != m) return r;
  for (size_t k = 0; k < m; ++k)
    if (!(A[k * m + k] > 0.0) || !(lo[k] <= hi[k])) return r;
  auto clamp = [&](size_t k, double v) { return std::min(hi[k], std::max(lo[k], v)); };
  auto residual = [&](size_t k) {
    double s = q[k];
    for (size_t j = 0; j < m; ++j) s += A[k * m + j] * r.x[j];
    return s;
  };
  // The guess: Gauss-Seidel on the box from the point of the box nearest 0.
  std::vector<double>& x = r.x;
  for (size_t k = 0; k < m; ++k) x[k] = clamp(k, 0.0);
  for (int sweep = 0; sweep < kGaussSeidelSweeps; ++sweep) {
    double change = 0.0, size = 0.0;
    for (size_t k = 0; k < m; ++k) {
      const double next = clamp(k, x[k] - residual(k) / A[k * m + k]);
      change = std::max(change, std::abs(next - x[k]));
      size = std::max(size, std::abs(next));
      x[k] = next;
    }
    if (change <= 1e-15 * (1.0 + size)) break;
  }
  for (size_t k = 0; k < m; ++k)
    r.state[k] = x[k] <= lo[k] ? BoxState::kLower : x[k] >= hi[k] ? BoxState::kUpper : BoxState::kFree;

  // The scales the conditions are read against.
  double q_max = 0.0, a_max = 0.0, b_max = 0.0;
  for (size_t k = 0; k < m; ++k) {
    q_max = std::max(q_max, std::abs(q[k]));
    a_max = std::max(a_max, A[k * m + k]);
    if (std::isfinite(lo[k])) b_max = std::max(b_max, std::abs(lo[k]));
    if (std::isfinite(hi[k])) b_max = std::max(b_max, std::abs(hi[k]));
  }
  const int max_pivots = 50 + 20 * static_cast<int>(m);
  std::vector<size_t> free_ids;
  for (int pivot = 0;; ++pivot) {
    // x: the bound ones at their bounds, the free ones from A_FF x_F = -(q_F + A_FB x_B).
    free_ids.clear();
    for (size_t k = 0; k < m; ++k) {
      if (r.state[k] == BoxState::kFree)
        free_ids.push_back(k);
      else
        x[k] = r.state[k] == BoxState::kLower ? lo[k] : hi[k];
    }
    if (!free_ids.empty()) {
      const auto n = static_cast<Eigen::Index>(free_ids.size());
      Eigen::MatrixXd AF(n, n);
      Eigen::VectorXd b(n);
      for (Eigen::Index i = 0; i < n; ++i) {
        const size_t ki = free_ids[static_cast<size_t>(i)];
        double s = -q[ki];
        for (size_t j = 0; j < m; ++j)
          if (r.state[j] != BoxState::kFree) s -= A[ki * m + j] * x[j];
        b[i] = s;
        for (Eigen::Index c = 0; c < n; ++c) AF(i, c) = A[ki * m + free_ids[static_cast<size_t>(c)]];
      }
      const Eigen::LLT<Eigen::MatrixXd> llt(AF);
      if (llt.info() != Eigen::Success) return r;  // not positive definite
      const Eigen::VectorXd xf = llt.solve(b);
      for (Eigen::Index i = 0; i < n; ++i) x[free_ids[static_cast<size_t>(i)]] = xf[i];
    }
    double x_max = b_max;
    for (size_t k = 0; k < m; ++k)
      if (std::isfinite(x[k])) x_max = std::max(x_max, std::abs(x[k]));
    const double w_tol = tol * (1.0 + q_max + a_max * x_max);
    for (size_t k = 0; k < m; ++k) r.w[k] = residual(k);
    // The first k whose condition fails changes its state.
    size_t bad = m;
    BoxState next = BoxState::kFree;
    for (size_t k = 0; k < m && bad == m; ++k) {
      const double x_tol = tol * (1.0 + std::abs(x[k]));
      switch (r.state[k]) {
        case BoxState::kFree:
          if (x[k] < lo[k] - x_tol) bad = k, next = BoxState::kLower;
          else if (x[k] > hi[k] + x_tol) bad = k, next = BoxState::kUpper;
          break;
        case BoxState::kLower:
          if (r.w[k] < -w_tol) bad = k, next = BoxState::kFree;
          break;
        case BoxState::kUpper:
          if (r.w[k] > w_tol) bad = k, next = BoxState::kFree;
          break;
      }
    }
    if (bad == m) {
      for (size_t k = 0; k < m; ++k) x[k] = clamp(k, x[k]);  // a free one within x_tol of its bound
      r.solved = true;
      r.pivots = pivot;
      return r;
    }
    if (pivot >= max_pivots) return r;
    r.state[bad] = next;
  }
}

}  // namespace kanesim::sim
