// What the bridge over a change point (sim/change_point_bridge.h) reads from the closed
// loops: rho at a state, the loops' names, and the two projections it applies to the states
// it extrapolates (runtime/runtime.h; docs/constraints.md "Singular configurations").
#include <Eigen/Cholesky>
#include <cmath>
#include <string>
#include <vector>

#include "runtime/constraints/constraints.h"
#include "runtime/engine/branch_monitor_internal.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

Workspace& MonitorWorkspace(BranchMonitor& m) { return *m.ws; }

double SingularRatioAt(const Program& p, BranchMonitor& m, double t, const double* y, int* near_loops) {
  Workspace& ws = *m.ws;
  if (UnpackState(p, ws, t, y) != 0) return -1.0;
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  ConstraintJacobian(p, ws);
  double rho = 1.0;
  NearestSingularLoop(p, m, &rho, near_loops);
  return rho;
}

const std::string& LoopName(const Program& p, int loop) { return p.loops[static_cast<size_t>(loop)].name; }

int ProjectByPartition(const Program& p, Workspace& ws, double t, const double* y, double* z) {
  if (UnpackState(p, ws, t, y) != 0) return 1;
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  if (ProjectStateByPartition(p, ws) != 0) return 1;
  PackState(p, ws, z);
  return 0;
}

// The tangent space's kinetic metric at y: beta (nu x nind, from Derivative, with its
// partition) and Mr = beta^T M beta, and r = beta^T M (u_raw - u_y) when raw is given. Taken
// through the bodies' velocities: for the free speeds x, the differences of the mass-centre
// and angular velocities from those of y's speeds (the prescribed speeds and the time terms
// cancel), so that beta's columns and raw - u_y enter the metric (Metric) as the motions they are.
int TangentMetric(const Program& p, Workspace& ws, double t, const double* y, const double* raw, Eigen::MatrixXd* beta,
                  Eigen::MatrixXd* Mr, Eigen::VectorXd* r) {
  const int nq = p.nq, nu = p.nu, n = StateSize(p);
  std::vector<double> f(static_cast<size_t>(n));
  if (Derivative(p, ws, t, y, f.data()) != 0) return 1;  // beta at y, with its partition
  *beta = ws.beta;
  const int nind = static_cast<int>(beta->cols());
  Mr->resize(nind, nind);
  r->setZero(nind);
  if (nind == 0) return 0;
  if (UnpackState(p, ws, t, y) != 0) return 1;
  PositionKinematics(p, ws);
  const size_t K = p.bodies.size();
  auto velocities = [&](const std::vector<double>& x, std::vector<Vec3>* v, std::vector<Vec3>* w) {
    for (int i = 0; i < nu; ++i) ws.u[p.u_free[static_cast<size_t>(i)]] = x[static_cast<size_t>(i)];
    VelocityKinematics(p, ws);
    *v = ws.v_WBcm;
    *w = ws.w_WB;
  };
  std::vector<double> uy(y + nq, y + nq + nu), x(uy);
  std::vector<Vec3> v0, w0, vd, wd;
  velocities(uy, &v0, &w0);
  if (raw != nullptr) {
    for (int i = 0; i < nu; ++i) x[static_cast<size_t>(i)] = raw[nq + i];
    velocities(x, &vd, &wd);
    for (size_t L = 0; L < K; ++L) {
      vd[L] -= v0[L];
      wd[L] -= w0[L];
    }
  }
  std::vector<std::vector<Vec3>> vc(static_cast<size_t>(nind)), wc(static_cast<size_t>(nind));
  for (int c = 0; c < nind; ++c) {
    for (int i = 0; i < nu; ++i) x[static_cast<size_t>(i)] = uy[static_cast<size_t>(i)] + (*beta)(i, c);
    velocities(x, &vc[static_cast<size_t>(c)], &wc[static_cast<size_t>(c)]);
    for (size_t L = 0; L < K; ++L) {
      vc[static_cast<size_t>(c)][L] -= v0[L];
      wc[static_cast<size_t>(c)][L] -= w0[L];
    }
  }
  for (int c = 0; c < nind; ++c) {
    const auto uc = static_cast<size_t>(c);
    if (raw != nullptr) (*r)[c] = Metric(p, ws, vc[uc], wc[uc], vd, wd);
    for (int d = 0; d < nind; ++d) (*Mr)(c, d) = Metric(p, ws, vc[uc], wc[uc], vc[static_cast<size_t>(d)], wc[static_cast<size_t>(d)]);
  }
  return 0;
}

int ProjectSpeedsInKineticMetric(const Program& p, Workspace& ws, double t, const double* raw, double* y) {
  const int nq = p.nq, nu = p.nu, n = StateSize(p);
  Eigen::MatrixXd beta, Mr;
  Eigen::VectorXd r;
  if (TangentMetric(p, ws, t, y, raw, &beta, &Mr, &r) != 0) return 1;
  if (beta.cols() == 0) return 0;
  Eigen::LLT<Eigen::MatrixXd> llt(Mr);
  if (llt.info() != Eigen::Success) return 1;
  const Eigen::VectorXd z = llt.solve(r);
  for (int i = 0; i < nu; ++i) y[nq + i] += beta.row(i).dot(z);
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(y[i])) return 1;
  return 0;
}

}  // namespace kanesim::rt
