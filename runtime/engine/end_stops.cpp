// End stops (runtime/runtime.h EndStops, InverseMassColumn): what the integrators' event
// handling (sim/end_stops.cpp) reads of the program: where each stop joint sits in the state,
// and the mass matrix's response to an impulse.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "runtime/engine/branch_monitor_internal.h"
#include "runtime/kane/kane.h"
#include "runtime/program/program.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

namespace {
// A speed whose constrained response is below this fraction of the largest is fixed by the rows.
constexpr double kDeadPoint = 1e-10;
}  // namespace

std::vector<EndStop> EndStops(const Program& p) {
  std::vector<EndStop> out;
  for (int b : p.stop_joints) {
    const TreeJoint& j = p.joints[static_cast<size_t>(b)];
    EndStop s;
    s.joint = j.name;
    s.q = static_cast<int>(std::find(p.q_free.begin(), p.q_free.end(), j.q0) - p.q_free.begin());
    s.u = p.u_free_of[static_cast<size_t>(j.u0)];
    s.q_min = j.q_min;
    s.q_max = j.q_max;
    s.restitution = j.restitution;
    out.push_back(s);
  }
  return out;
}

// Closed loops and rolling contacts: the impulse F lambda plus the rows' reactions A^T mu
// keeping A du = 0 (M du = A^T mu + F lambda) moves the speeds in the tangent space,
// du = beta z with (beta^T M beta) z = beta^T F: x = W F, W = beta Mr^-1 beta^T. F^T W F ~ 0
// where the rows fix the motion F acts on (a dead point): -1, the jump would need an
// unbounded impulse. `what` names that motion in the message.
int ConstrainedInverseMassTimes(const Program& p, Workspace& ws, double t, const double* y, const double* F,
                                const std::string& what, double* x) {
  Eigen::MatrixXd beta, Mr;
  Eigen::VectorXd r;
  if (p.solver == SolverPath::Sparse) {  // the multiplier form has no tangent basis
    ws.error = "an impulse in a mechanism with closed loops or contacts needs the reduced form (not --solver sparse)";
    return -1;
  }
  if (TangentMetric(p, ws, t, y, nullptr, &beta, &Mr, &r) != 0) return 1;
  if (beta.rows() != p.nu) {
    ws.error = "an impulse in a mechanism with closed loops or contacts needs the reduced form (not --solver sparse)";
    return -1;
  }
  std::fill(x, x + p.nu, 0.0);
  const Eigen::LLT<Eigen::MatrixXd> llt(Mr);
  if (beta.cols() == 0 || llt.info() != Eigen::Success) {
    ws.error = "the closed loops or contacts leave no motion at time " + std::to_string(t);
    return -1;
  }
  const Eigen::MatrixXd W = beta * llt.solve(beta.transpose());  // the constrained inverse mass
  const Eigen::Map<const Eigen::VectorXd> f(F, p.nu);
  const Eigen::VectorXd col = W * f;
  const double scale = W.diagonal().cwiseAbs().maxCoeff();
  if (!(f.dot(col) > kDeadPoint * scale * f.squaredNorm())) {
    ws.error = "the closed loops or contacts fix " + what + " here (a dead point: its jump would need an unbounded impulse)";
    return -1;
  }
  for (int i = 0; i < p.nu; ++i) x[i] = col[i];
  return 0;
}

// Columns of M^-1 from the assembled mass matrix (Cholesky), one factorization for all. A
// difference of two accelerations (applied unit force vs none) lost the column to rounding
// where the accelerations were large, as at an integrator's trial stage far from the solution.
int InverseMassColumns(const Program& p, Workspace& ws, double t, const double* y, const int* ks, int m, double* X) {
  if (FrictionReadsNormalForce(p)) {
    ws.error = "an impulse in a mechanism with Coulomb friction mu N is not supported yet";
    return -1;
  }
  return FrictionlessInverseMassColumns(p, ws, t, y, ks, m, X);
}

int FrictionlessInverseMassColumns(const Program& p, Workspace& ws, double t, const double* y, const int* ks, int m,
                                   double* X) {
  if (m == 0) return 0;
  if (!p.rows.empty()) {  // (one factorization per column: TangentMetric's basis for each)
    for (int j = 0; j < m; ++j) {
      std::vector<double> e(static_cast<size_t>(p.nu), 0.0);
      e[static_cast<size_t>(ks[j])] = 1.0;
      ++ws.inverse_mass_factorizations;
      if (int s = ConstrainedInverseMassTimes(p, ws, t, y, e.data(),
                                              "'" + StateNames(p)[static_cast<size_t>(p.nq + ks[j])] + "'",
                                              X + static_cast<size_t>(j) * static_cast<size_t>(p.nu));
          s != 0)
        return s;
    }
    return 0;
  }
  // M depends on t and q only: the factor of the last call is kept for the same (t, q) (the
  // event functions after a right-hand side at that state, the stops' after the friction's),
  // and so is each column solved from it: a held solve asks for the same columns several
  // times at one state (the friction's two passes, then the stops' reactions), and a column
  // solved again from the same factor is the same to the bit.
  const size_t nu = static_cast<size_t>(p.nu);
  std::vector<double>& at = ws.inverse_mass_at;
  if (at.size() != static_cast<size_t>(p.nq) + 1 || at[0] != t || !std::equal(y, y + p.nq, at.begin() + 1)) {
    at.clear();  // (a failed evaluation keeps no factor)
    Eigen::MatrixXd M(p.nu, p.nu);
    if (int s = MassMatrix(p, ws, t, y, M.data()); s != 0) return s;
    ++ws.inverse_mass_factorizations;
    ws.inverse_mass_llt.compute(M);
    ws.inverse_mass_M.assign(M.data(), M.data() + M.size());
    at.push_back(t);
    at.insert(at.end(), y, y + p.nq);
    ws.inverse_mass_cols.resize(nu * nu);
    ws.inverse_mass_known.assign(nu, 0);
  }
  const Eigen::LLT<Eigen::MatrixXd>& llt = ws.inverse_mass_llt;
  for (int j = 0; j < m; ++j) {
    const int k = ks[j];
    double* kept = ws.inverse_mass_cols.data() + static_cast<size_t>(k) * nu;
    if (!ws.inverse_mass_known[static_cast<size_t>(k)]) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(p.nu);
      e[k] = 1.0;
      Eigen::VectorXd col = Eigen::VectorXd::Zero(p.nu);
      if (llt.info() == Eigen::Success) col = llt.solve(e);  // column by column: each as alone
      if (!(col[k] > 0.0) || !col.allFinite()) {  // M is positive definite: (M^-1)_kk > 0
        ws.error = "the mass matrix is singular for an impulse on speed " + std::to_string(k) + " at time " + std::to_string(t);
        return 1;  // recoverable: a trial stage may probe a state far from the solution
      }
      std::copy(col.data(), col.data() + p.nu, kept);
      ws.inverse_mass_known[static_cast<size_t>(k)] = 1;
    }
    std::copy(kept, kept + nu, X + static_cast<size_t>(j) * nu);
  }
  return 0;
}

bool KeptMassMatrix(const Program& p, const Workspace& ws, double t, const double* y, double* M) {
  const std::vector<double>& at = ws.inverse_mass_at;
  if (!p.rows.empty() || at.size() != static_cast<size_t>(p.nq) + 1 || at[0] != t || !std::equal(y, y + p.nq, at.begin() + 1))
    return false;
  std::copy(ws.inverse_mass_M.begin(), ws.inverse_mass_M.end(), M);
  return true;
}

int InverseMassColumn(const Program& p, Workspace& ws, double t, const double* y, int k, double* x) {
  return InverseMassColumns(p, ws, t, y, &k, 1, x);
}

EvalCounts Counts(const Workspace& ws) { return {ws.derivatives, ws.inverse_mass_factorizations}; }

// Derivative's evaluation with F on the speeds beside the applied forces (the friction's
// normal-force iteration and, with constraint rows, their reactions and the pull to the
// manifold included, as for any force).
int DerivativeWithForces(const Program& p, Workspace& ws, double t, const double* y, const double* F, double* ydot) {
  ws.added_forces = F;
  const int s = Derivative(p, ws, t, y, ydot);
  ws.added_forces = nullptr;
  return s;
}

void SetHeldLoads(const Program& p, Workspace& ws, const double* F, const std::vector<std::pair<int, double>>& planes,
                  const std::vector<int>& speeds) {
  ws.held_F.clear();
  if (F) ws.held_F.assign(F, F + p.nu);
  ws.held_planes = planes;
  ws.held_speeds = speeds;
}

void ClearHeldLoads(Workspace& ws) {
  ws.held_F.clear();
  ws.held_planes.clear();
  ws.held_speeds.clear();
}

}  // namespace kanesim::rt
