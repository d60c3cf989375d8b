// Output rows near a change point (output_rows.h; docs/constraints.md "Rows near a change
// point").
#include "runtime/engine/output_rows.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "runtime/constraints/constraints.h"
#include "runtime/runtime.h"
#include "runtime/kane/kane.h"
#include "runtime/kinematics/kinematics.h"

namespace kanesim::rt {
namespace {

// A row is near a change point below this rho of a loop's rows (the branch monitor's zone,
// branch_monitor.cpp kZone).
constexpr double kRowZone = 1e-2;
// Singular values of the metric-scaled Jacobian below this fraction of the largest are
// left out of the correction (their directions keep the integrator's values). Measured on
// the chain of 40 (CVODE, rtol 1e-6): 1e-3 left the rods' speeds up to 2e-5 apart in rows
// where the partition's projection had them 1e-9 apart; 1e-7 and below gave back the row
// the partition spoilt (8e-3 apart; the position residual's amplification).
constexpr double kTruncate = 1e-5;
constexpr int kMaxGaussNewton = 8;
// The positions' Gauss-Newton goes on below kProjectTight (1e-13 of the loops' length) to this
// round-off: near a crossing a residual c of the positions makes the rods' speeds differ by
// ~ omega c / (2 a^2 theta^2), visible in the energy (measurements: docs/constraints/2026-11-28_tuning_measurements.md).
constexpr double kRowRoundOff = 1e-16;

// The kinetic-energy metric on the free speeds, M = sum_L m_L Jv_L^T Jv_L + Jw_L^T I_L Jw_L,
// by one velocity pass per free speed (only for the few rows near a change point).
Eigen::MatrixXd KineticMetric(const Program& p, Workspace& ws) {
  const Eigen::VectorXd u = ws.u;
  const size_t K = p.bodies.size();
  for (int s = 0; s < p.nu; ++s) ws.u[p.u_free[static_cast<size_t>(s)]] = 0.0;
  VelocityKinematics(p, ws);
  const std::vector<Vec3> v0 = ws.v_WBcm, w0 = ws.w_WB;
  Eigen::MatrixXd Jv(3 * K, p.nu), Jw(3 * K, p.nu);
  for (int s = 0; s < p.nu; ++s) {
    const int f = p.u_free[static_cast<size_t>(s)];
    ws.u[f] = 1.0;
    VelocityKinematics(p, ws);
    ws.u[f] = 0.0;
    for (size_t L = 0; L < K; ++L) {
      Jv.block<3, 1>(3 * static_cast<Eigen::Index>(L), s) = ws.v_WBcm[L] - v0[L];
      Jw.block<3, 1>(3 * static_cast<Eigen::Index>(L), s) = ws.w_WB[L] - w0[L];
    }
  }
  ws.u = u;
  VelocityKinematics(p, ws);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(p.nu, p.nu);
  for (size_t L = 0; L < K; ++L) {
    const auto r = 3 * static_cast<Eigen::Index>(L);
    const auto jv = Jv.middleRows<3>(r);
    const auto jw = Jw.middleRows<3>(r);
    M.noalias() += p.bodies[L].mass * (jv.transpose() * jv);
    M.noalias() += jw.transpose() * (ws.I_W[L] * jw);
  }
  return M;
}

// The correction of least kinetic energy: du (free speeds) with A du = -r on the active rows,
// through the truncated pseudo-inverse of A L^-T (M = L L^T).
struct MetricSolve {
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::MatrixXd At;  // (A L^-T)^T
  Eigen::JacobiSVD<Eigen::MatrixXd> svd;
  void Factor(const Eigen::MatrixXd& A) {
    At = llt.matrixL().solve(A.transpose());
    svd.compute(At.transpose(), Eigen::ComputeThinU | Eigen::ComputeThinV);
  }
  Eigen::VectorXd Step(const Eigen::VectorXd& r) const {
    const auto& s = svd.singularValues();
    Eigen::VectorXd c = svd.matrixU().transpose() * r;
    const double cut = s.size() > 0 ? kTruncate * s[0] : 0.0;
    for (Eigen::Index i = 0; i < c.size(); ++i) c[i] = s[i] > cut ? -c[i] / s[i] : 0.0;
    Eigen::VectorXd w = svd.matrixV() * c;
    return llt.matrixU().solve(w);  // L^-T w
  }
};

Eigen::VectorXd Active(const Program& p, const Eigen::VectorXd& full) {
  Eigen::VectorXd a(static_cast<Eigen::Index>(p.active_rows.size()));
  for (size_t k = 0; k < p.active_rows.size(); ++k) a[static_cast<Eigen::Index>(k)] = full[p.active_rows[k]];
  return a;
}

}  // namespace

bool RowNearChangePoint(const Program& p, Workspace& ws) {
  if (p.loops.empty() || p.loop_rank == 0) return false;
  VelocityKinematics(p, ws);
  ConstraintJacobian(p, ws);
  for (size_t l = 0; l < p.loops.size(); ++l)
    if (double length = 0.0; LoopSingularRatio(p, ws, static_cast<int>(l), &length) < kRowZone) return true;
  return false;
}

int ProjectRowNearChangePoint(const Program& p, Workspace& ws, bool accelerations) {
  VelocityKinematics(p, ws);
  MetricSolve ms;
  Eigen::MatrixXd M = KineticMetric(p, ws);
  ms.llt.compute(M);
  if (ms.llt.info() != Eigen::Success) {  // a speed that moves no mass: a little of the Euclidean metric
    const double d = 1e-12 * std::max(1e-300, M.diagonal().cwiseAbs().maxCoeff());
    M.diagonal().array() += d;
    ms.llt.compute(M);
  }
  // Positions: Gauss-Newton steps of least kinetic metric, to round-off (kRowRoundOff) or
  // until the residual stops halving; the positions of the smallest residual are kept.
  double last = INFINITY, best = INFINITY;
  Eigen::VectorXd q_best;
  for (int it = 0; it < kMaxGaussNewton; ++it) {
    ConstraintResiduals(p, ws);
    const double r = ws.phi.cwiseAbs().maxCoeff();
    if (r < best) {
      best = r;
      q_best = ws.q;
    }
    if (r <= kRowRoundOff * p.loop_length || r > 0.5 * last) break;
    last = r;
    ConstraintJacobian(p, ws);
    ms.Factor(ws.A);
    const Eigen::VectorXd dq = ms.Step(Active(p, ws.phi));
    ws.du_full.setZero();
    for (int s = 0; s < p.nu; ++s) ws.du_full[p.u_free[static_cast<size_t>(s)]] = dq[s];
    StepCoordinates(p, ws);
  }
  ConstraintResiduals(p, ws);
  if (ws.phi.cwiseAbs().maxCoeff() > best) {  // the last step went up from round-off
    ws.q = q_best;
    PositionKinematics(p, ws);
    VelocityKinematics(p, ws);
  }
  ConstraintResiduals(p, ws);
  if (int s = CheckLoopsClosed(p, ws); s != 0) return s;
  // Speeds: one step (linear).
  ConstraintJacobian(p, ws);
  ms.Factor(ws.A);
  const Eigen::VectorXd du = ms.Step(Active(p, ws.psi));
  for (int s = 0; s < p.nu; ++s) ws.u[p.u_free[static_cast<size_t>(s)]] += du[s];
  VelocityKinematics(p, ws);
  ConstraintJacobian(p, ws);  // psi of the projected speeds
  if (int s = CheckDisksUpright(p, ws); s != 0) return s;
  if (p.solver == SolverPath::Sparse) {
    ws.sparse_ready = false;  // SolveSparse factors at these positions
  } else if (FactorDependent(p, ws) != 0) {  // at the crossing itself
    if (accelerations) return 1;             // they are not determined there (ws.error says so)
    ws.error.clear();
  }
  return 0;
}

}  // namespace kanesim::rt
