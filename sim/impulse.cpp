#include "sim/impulse.h"

#include <cmath>
#include <utility>

namespace kanesim::sim {

bool SolveSmall(std::vector<double> A, std::vector<double> b, std::vector<double>* c) {
  const size_t m = b.size();
  for (size_t k = 0; k < m; ++k) {
    size_t p = k;
    for (size_t r = k + 1; r < m; ++r)
      if (std::abs(A[r * m + k]) > std::abs(A[p * m + k])) p = r;
    if (!(A[p * m + k] != 0.0)) return false;
    for (size_t j = 0; j < m; ++j) std::swap(A[k * m + j], A[p * m + j]);
    std::swap(b[k], b[p]);
    for (size_t r = k + 1; r < m; ++r) {
      const double f = A[r * m + k] / A[k * m + k];
      for (size_t j = k; j < m; ++j) A[r * m + j] -= f * A[k * m + j];
      b[r] -= f * b[k];
    }
  }
  c->assign(m, 0.0);
  for (size_t k = m; k-- > 0;) {
    double s = b[k];
    for (size_t j = k + 1; j < m; ++j) s -= A[k * m + j] * (*c)[j];
    (*c)[k] = s / A[k * m + k];
  }
  return true;
}

int SpeedJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
              const std::vector<double>& targets, double* du) {
  const size_t m = rows.size(), nu = static_cast<size_t>(rt::NumU(program));
  for (size_t i = 0; i < nu; ++i) du[i] = 0.0;
  if (m == 0) return 0;
  std::vector<double> X(m * nu), A(m * m), c;
  for (size_t j = 0; j < m; ++j)
    if (int s = rt::InverseMassColumn(program, ws, t, y, rows[j], X.data() + j * nu); s != 0) return s;
  for (size_t r = 0; r < m; ++r)
    for (size_t j = 0; j < m; ++j) A[r * m + j] = X[j * nu + static_cast<size_t>(rows[r])];
  if (!SolveSmall(A, targets, &c)) return -1;
  for (size_t i = 0; i < nu; ++i)
    for (size_t j = 0; j < m; ++j) du[i] += X[j * nu + i] * c[j];
  return 0;
}

}  // namespace kanesim::sim
