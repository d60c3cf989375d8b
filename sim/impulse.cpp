#include "sim/impulse.h"

#include "runtime/program/program.h"  // Program::contacts

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace kanesim::sim {

namespace {
// A contact's normal impulse below -kPullTolerance times the jump's largest impulse pulls.
constexpr double kPullTolerance = 1e-9;
// Held rows scaled to a unit diagonal whose elimination meets a pivot below this are
// dependent (the exactly dependent four corners of a flat box give about 1e-16; rows this
// close to dependent would need impulses 1e10 times their scale, which say nothing).
constexpr double kDependentPivot = 1e-10;
// Dependent held rows are consistent when A c = b is met to this much of its terms.
constexpr double kConsistentRows = 1e-8;
}  // namespace

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

bool SolveHeld(const std::vector<double>& A, const std::vector<double>& b, std::vector<double>* c, bool* dependent,
               double slack) {
  const size_t m = b.size();
  if (dependent) *dependent = false;
  // The rows scaled to a unit diagonal (a scale-free test: a stop's row in N m beside a
  // plane's in N, a light link's beside a heavy one's), then eliminated: a pivot below
  // kDependentPivot means a row is a combination of the others to round-off.
  std::vector<double> d(m);
  bool singular = false;
  for (size_t i = 0; i < m; ++i) {
    const double a = A[i * m + i];
    if (!std::isfinite(a)) return false;
    singular = singular || !(a > 0.0);
    d[i] = a > 0.0 ? 1.0 / std::sqrt(a) : 1.0;
  }
  Eigen::MatrixXd S(m, m);
  for (size_t r = 0; r < m; ++r)
    for (size_t j = 0; j < m; ++j) S(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(j)) = d[r] * A[r * m + j] * d[j];
  if (!S.allFinite()) return false;
  if (!singular) {
    Eigen::MatrixXd U = S;  // Gaussian elimination, partial pivoting (A is symmetric: no growth)
    const Eigen::Index n = U.rows();
    for (Eigen::Index k = 0; k < n && !singular; ++k) {
      Eigen::Index p = k;
      U.col(k).tail(n - k).cwiseAbs().maxCoeff(&p);
      p += k;
      if (!(std::abs(U(p, k)) > kDependentPivot)) {
        singular = true;
        break;
      }
      U.row(k).swap(U.row(p));
      for (Eigen::Index r = k + 1; r < n; ++r) U.row(r).tail(n - k) -= U(r, k) / U(k, k) * U.row(k).tail(n - k);
    }
  }
  if (!singular) return SolveSmall(A, b, c);
  if (dependent) *dependent = true;
  Eigen::VectorXd sb(m);
  for (size_t i = 0; i < m; ++i) sb(static_cast<Eigen::Index>(i)) = d[i] * b[i];
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
  cod.setThreshold(kDependentPivot);
  cod.compute(S);
  const Eigen::VectorXd y = cod.solve(sb);
  c->resize(m);
  for (size_t i = 0; i < m; ++i) (*c)[i] = d[i] * y(static_cast<Eigen::Index>(i));
  // Consistent: the targets are in the rows' range (they are where each comes from the same
  // motion: a flat box's four corners approach the floor at one speed), to round-off.
  for (size_t r = 0; r < m; ++r) {
    double Ac = 0.0, terms = std::abs(b[r]);
    for (size_t j = 0; j < m; ++j) Ac += A[r * m + j] * (*c)[j], terms += std::abs(A[r * m + j] * (*c)[j]);
    if (!(std::abs(Ac - b[r]) <= kConsistentRows * terms + slack)) return false;
  }
  return true;
}

int SpeedJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
              const std::vector<double>& targets, double* du, std::vector<double>* F) {
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
  if (F) {
    F->assign(nu, 0.0);
    for (size_t j = 0; j < m; ++j) (*F)[static_cast<size_t>(rows[j])] += c[j];
  }
  return 0;
}

std::string PullingContact(const rt::Program& program, rt::Workspace& ws, double t, const double* y,
                           const std::vector<double>& du, const std::vector<double>& F, int* status) {
  *status = 0;
  const size_t nc = program.contacts.size();
  if (nc == 0) return "";
  std::vector<double> P(nc);
  if ((*status = rt::ContactNormalImpulses(program, ws, t, y, du.data(), F.data(), P.data())) != 0)
    return rt::ErrorMessage(ws);
  // Round-off: the impulses' scale (the contacts' and the joints' own) times a few ulps of
  // the least-squares solve.
  double scale = 0.0;
  for (double v : P) scale = std::max(scale, std::abs(v));
  for (double v : F) scale = std::max(scale, std::abs(v));
  for (size_t i = 0; i < nc; ++i) {
    // A normal impulse the equations do not determine (a row redundant with a joint) says
    // nothing about pulling, as LiftOffGuard leaves its force unguarded.
    if (!program.contact_indeterminate.empty() && (program.contact_indeterminate[i] & 1u) != 0) continue;
    if (P[i] >= -kPullTolerance * scale) continue;
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  "contact '%s': its normal impulse in the speed jump is tensile (%.6g N s: the plane would have to "
                  "pull the body onto it); a rolling contact cannot lift off (docs/events.md \"Rolling contacts in a "
                  "jump\")",
                  program.contacts[i].name.c_str(), P[i]);
    return buf;
  }
  return "";
}

}  // namespace kanesim::sim
