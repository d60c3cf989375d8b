#include "sim/dq_jacobian.h"

#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>

namespace kanesim::sim::detail {
namespace {
constexpr double kRoundOff = 2.220446049250313e-16;
}  // namespace

void DqJacobian::Build(int n, const std::vector<int>& coupling, Increment rule) {
  n_ = n;
  rule_ = rule;
  const auto un = static_cast<size_t>(n);
  group_.assign(un, 0);
  if (coupling.size() == un) group_ = coupling;
  const int ngroups = n > 0 ? *std::max_element(group_.begin(), group_.end()) + 1 : 0;
  members_.assign(static_cast<size_t>(ngroups), {});
  for (int i = 0; i < n; ++i) members_[static_cast<size_t>(group_[static_cast<size_t>(i)])].push_back(i);
  size_t ncolors = 0;
  for (const auto& m : members_) ncolors = std::max(ncolors, m.size());
  colors_.assign(ncolors, {});
  for (const auto& m : members_)
    for (size_t k = 0; k < m.size(); ++k) colors_[k].push_back(m[k]);
  col_start_.assign(un + 1, 0);
  for (size_t j = 0; j < un; ++j)
    col_start_[j + 1] = col_start_[j] + static_cast<sunindextype>(members_[static_cast<size_t>(group_[j])].size());
  nnz_ = col_start_.back();
  f1_.assign(un, 0.0);
  y1_.assign(un, 0.0);
  inc_.assign(un, 0.0);
  skip_.assign(un, 0);
}

void DqJacobian::SetLayout(bool sparse) {
  sparse_ = sparse;
  const auto un = static_cast<size_t>(n_);
  dfdy_.assign(sparse ? static_cast<size_t>(nnz_) : un * un, 0.0);
}

int DqJacobian::Form(GuardedRhs& rhs, double t, const double* y, const double* yp, const double* f0, double h,
                     const double* w) {
  const auto un = static_cast<size_t>(n_);
  const double srur = std::sqrt(kRoundOff);
  std::copy(y, y + n_, y1_.begin());
  // The last evaluation was at y: its discrete choices (the loops' speed partition) are
  // held for the perturbed ones.
  GuardedRhs::JacobianHold hold(rhs);
  // Columns of the states f does not read under that partition (closed loops on the
  // reduced form: the dependent speeds and coordinates, recomputed by the projection) are
  // known without evaluations: df/dy = pdiag on the diagonal (the pull to the manifold),
  // zero elsewhere. Perturbed, they only measured the projection's Newton tolerance (up to
  // 4e3 against IDA's cj 6e4 near a change point of the chain of ten) and cost n - 2 of
  // the n evaluations on a chain of loops.
  const bool cvode = rule_ == Increment::kCvode;
  double min_inc = 0.0;
  if (cvode) {
    double fn = 0.0;
    for (int i = 0; i < n_; ++i) fn += (f0[i] * w[i]) * (f0[i] * w[i]);
    fn = std::sqrt(fn / n_);
    min_inc = fn != 0.0 ? 1000.0 * std::fabs(h) * kRoundOff * n_ * fn : 1.0;
  }
  double pdiag = 0.0;
  std::fill(skip_.begin(), skip_.end(), 0);
  if (rhs.ProjectedStates(&projected_, &pdiag))
    for (int j : projected_) skip_[static_cast<size_t>(j)] = 1;
  for (const auto& color : colors_) {
    bool any = false;
    for (int j : color) {
      const auto uj = static_cast<size_t>(j);
      if (skip_[uj]) continue;
      any = true;
      double inc = 0.0;
      if (cvode) {
        inc = std::max(srur * std::fabs(y[j]), (floor_ ? std::max(min_inc, 1.0) : min_inc) / w[j]);
      } else {
        inc = std::max(srur * std::max(std::fabs(y[j]), std::fabs(h * yp[j])), 1.0 / w[j]);
        if (h * yp[j] < 0.0) inc = -inc;
      }
      y1_[uj] = y[j] + inc;
      inc_[uj] = y1_[uj] - y[j];  // the increment actually represented
    }
    int status = 0;
    if (any) {
      ++evals_;
      status = rhs(t, y1_.data(), f1_.data());
      for (int j : color) y1_[static_cast<size_t>(j)] = y[j];
    }
    if (status != 0) return status;
    for (int j : color) {
      const auto uj = static_cast<size_t>(j);
      const auto& m = members_[static_cast<size_t>(group_[uj])];
      for (size_t k = 0; k < m.size(); ++k) {
        const auto i = static_cast<size_t>(m[k]);
        const double d = skip_[uj] ? (m[k] == j ? pdiag : 0.0) : (f1_[i] - f0[i]) / inc_[uj];
        dfdy_[sparse_ ? static_cast<size_t>(col_start_[uj]) + k : uj * un + i] = d;
      }
    }
  }
  return 0;
}

void DqJacobian::WritePattern(SUNMatrix J) const {
  sunindextype* ptr = SUNSparseMatrix_IndexPointers(J);
  sunindextype* idx = SUNSparseMatrix_IndexValues(J);
  for (int j = 0; j <= n_; ++j) ptr[j] = col_start_[static_cast<size_t>(j)];
  for (int j = 0; j < n_; ++j) {
    const auto& m = members_[static_cast<size_t>(group_[static_cast<size_t>(j)])];
    for (size_t k = 0; k < m.size(); ++k) idx[col_start_[static_cast<size_t>(j)] + static_cast<sunindextype>(k)] = m[k];
  }
}

void DqJacobian::WriteNewton(double cj, SUNMatrix J) const {
  const auto un = static_cast<size_t>(n_);
  if (sparse_) {
    WritePattern(J);
    double* data = SUNSparseMatrix_Data(J);
    for (int j = 0; j < n_; ++j) {
      const auto& m = members_[static_cast<size_t>(group_[static_cast<size_t>(j)])];
      for (size_t k = 0; k < m.size(); ++k) {
        const auto e = static_cast<size_t>(col_start_[static_cast<size_t>(j)]) + k;
        data[e] = m[k] == j ? cj - dfdy_[e] : -dfdy_[e];
      }
    }
    return;
  }
  SUNMatZero(J);
  for (int j = 0; j < n_; ++j) {
    double* col = SUNDenseMatrix_Column(J, j);
    const double* d = dfdy_.data() + static_cast<size_t>(j) * un;
    for (int i : members_[static_cast<size_t>(group_[static_cast<size_t>(j)])]) col[i] = i == j ? cj - d[i] : -d[i];
  }
}

void DqJacobian::WriteDfdy(SUNMatrix J) const {
  const auto un = static_cast<size_t>(n_);
  SUNMatZero(J);
  for (int j = 0; j < n_; ++j) {
    double* col = SUNDenseMatrix_Column(J, j);
    const double* d = dfdy_.data() + static_cast<size_t>(j) * un;
    for (int i : members_[static_cast<size_t>(group_[static_cast<size_t>(j)])]) col[i] = d[i];
  }
}

}  // namespace kanesim::sim::detail
