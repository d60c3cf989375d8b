// The response to an impulse with Coulomb friction's normal impulses (runtime/runtime.h
// ImpulseResponse): what a jump with `mu` friction (sim/friction_impulse.cpp) reads. During
// an impulse the bodies' forces and velocity terms are bounded, so the Newton-Euler sum of
// reactions.cpp (5) keeps only the momentum jumps and the other impulses: the impulse the
// parent side gives the subtree below joint L through the joint is
//   P_L = sum_{B in subtree(L)} m_B dv_cm,B - (rows' impulses on the subtree)        (1)
// The rows' (closed loops', rolling contacts', couplings') impulses mu solve
//   A^T mu = M du - F                                                                (2)
// (M du = A^T mu + F, F the generalized impulse on the joints), minimum-norm on the active
// rows as LoopMultipliers takes the forces' (the same share where rows are redundant). The
// joints' generalized impulses (a reinit's, a stop's, friction's) act along their joints'
// axes, between two bodies of the same subtree or on L's own axis, and so add nothing
// across L's axis. That part of P_L is the joint's normal impulse, as friction.cpp (1)
// takes N from the reaction force:
//   P_N,L = P_L - (P_L . a) a                                                        (3)
// Everything is linear in F: du = W F, W = M^-1 on a tree, beta (beta^T M beta)^-1 beta^T
// with rows (the jump keeps A du = 0), so both maps are returned as matrices, one column
// per unit impulse.
#include <Eigen/Dense>
#include <algorithm>
#include <vector>

#include "runtime/constraints/constraints.h"
#include "runtime/constraints/contacts.h"  // ContactAt, ContactRowDirection
#include "runtime/constraints/reactions.h"
#include "runtime/engine/branch_monitor_internal.h"  // TangentMetric
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

namespace {

// W = beta (beta^T M beta)^-1 beta^T at y; Derivative's partition and kinematics at y left in ws.
int ConstrainedInverseMass(const Program& p, Workspace& ws, double t, const double* y, Eigen::MatrixXd* W) {
  if (p.solver == SolverPath::Sparse) {
    ws.error = "an impulse in a mechanism with closed loops or contacts needs the reduced form (not --solver sparse)";
    return -1;
  }
  Eigen::MatrixXd beta, Mr;
  Eigen::VectorXd r;
  if (int s = TangentMetric(p, ws, t, y, nullptr, &beta, &Mr, &r); s != 0) return s;
  if (beta.rows() != p.nu) {
    ws.error = "an impulse in a mechanism with closed loops or contacts needs the reduced form (not --solver sparse)";
    return -1;
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(Mr);
  if (beta.cols() == 0 || llt.info() != Eigen::Success) {
    ws.error = "the closed loops or contacts leave no motion for an impulse at time " + std::to_string(t);
    return -1;
  }
  *W = beta * llt.solve(beta.transpose());
  return 0;
}

}  // namespace

int ImpulseResponse(const Program& p, Workspace& ws, double t, const double* y, double* W_out, double* N_out) {
  const int nu = p.nu;
  const size_t K = p.bodies.size(), nf = p.friction_joints.size();
  Eigen::MatrixXd W(nu, nu), M(nu, nu);
  if (!p.rows.empty()) {
    if (int s = ConstrainedInverseMass(p, ws, t, y, &W); s != 0) return s;
  }
  if (int s = UnconstrainedMassMatrix(p, ws, t, y, M.data()); s != 0) return s;
  if (p.rows.empty()) {
    const Eigen::LLT<Eigen::MatrixXd> llt(M);
    if (llt.info() != Eigen::Success) {
      ws.error = "the mass matrix is singular for an impulse at time " + std::to_string(t);
      return -1;
    }
    W = llt.solve(Eigen::MatrixXd::Identity(nu, nu));
  }
  std::copy(W.data(), W.data() + W.size(), W_out);
  if (nf == 0) return 0;
  // UnconstrainedMassMatrix left the positions and velocities of y in ws.
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> rows_t;
  bool rows = false;  // active rows carrying impulses
  if (!p.rows.empty()) {
    ConstraintJacobian(p, ws);
    rows = ws.A.rows() > 0;
    if (rows) rows_t.compute(ws.A.transpose());  // (2) minimum-norm
  }
  const std::vector<Vec3> v0 = ws.v_WBcm;
  const Eigen::VectorXd u_y = ws.u;
  Eigen::Map<Eigen::MatrixXd> N(N_out, static_cast<Eigen::Index>(3 * nf), nu);
  std::vector<Vec3> mom(K);
  for (int k = 0; k < nu; ++k) {
    const Eigen::VectorXd du = W.col(k);
    ws.u = u_y;
    for (int i = 0; i < nu; ++i) ws.u[p.u_free[static_cast<size_t>(i)]] += du[i];
    VelocityKinematics(p, ws);  // the velocities are affine in u: the difference is du's alone
    for (size_t L = 0; L < K; ++L) mom[L] = p.bodies[L].mass * (ws.v_WBcm[L] - v0[L]);
    for (size_t L = K; L-- > 0;)  // (1): children before parents (tree order reversed)
      if (const int parent = p.joints[L].parent; parent >= 0) mom[static_cast<size_t>(parent)] += mom[L];
    if (rows) {
      Eigen::VectorXd g = M * du;
      g[k] -= 1.0;  // F = e_k
      const Eigen::VectorXd mu = rows_t.solve(g);
      ws.lambda_c.setZero();
      for (size_t r = 0; r < p.active_rows.size(); ++r) ws.lambda_c[p.active_rows[r]] = mu[static_cast<Eigen::Index>(r)];
      MultiplierReactions(p, ws);  // minus the rows' impulses on each subtree
      for (size_t L = 0; L < K; ++L) mom[L] += ws.reaction_W[L].head<3>();
    }
    for (size_t i = 0; i < nf; ++i) {
      const auto L = static_cast<size_t>(p.friction_joints[i]);
      const Vec3 a = ws.R_WB[L] * p.joints[L].axis;  // the axis is fixed in both joint frames
      const Vec3 n = mom[L] - mom[L].dot(a) * a;     // (3)
      for (int c = 0; c < 3; ++c) N(static_cast<Eigen::Index>(3 * i) + c, k) = n[c];
    }
  }
  ws.u = u_y;
  VelocityKinematics(p, ws);
  return 0;
}

}  // namespace kanesim::rt

namespace kanesim::rt {

// The rows' impulses of a jump du by the generalized impulse F: A^T mu = M du - F (2),
// minimum-norm; each contact's normal impulse is n . sum_rows mu_r d_r (its rows' directions,
// as ContactForce sums the forces' multipliers).
int ContactNormalImpulses(const Program& p, Workspace& ws, double t, const double* y, const double* du,
                          const double* F, double* P) {
  const size_t nc = p.contacts.size();
  std::fill(P, P + nc, 0.0);
  if (nc == 0) return 0;
  const int nu = p.nu;
  Eigen::MatrixXd M(nu, nu);
  if (int s = UnconstrainedMassMatrix(p, ws, t, y, M.data()); s != 0) return s;
  ConstraintJacobian(p, ws);  // at y's positions and velocities, which UnconstrainedMassMatrix left
  if (ws.A.rows() == 0) return 0;
  const Eigen::VectorXd g = M * Eigen::Map<const Eigen::VectorXd>(du, nu) - Eigen::Map<const Eigen::VectorXd>(F, nu);
  const Eigen::VectorXd mu = Eigen::MatrixXd(ws.A.transpose()).completeOrthogonalDecomposition().solve(g);
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(p.rows.size()));
  for (size_t r = 0; r < p.active_rows.size(); ++r) lambda[p.active_rows[r]] = mu[static_cast<Eigen::Index>(r)];
  for (size_t i = 0; i < nc; ++i) {
    const ContactModel& c = p.contacts[i];
    const ContactPoint cp = ContactAt(p, ws, c);
    Vec3 imp = Vec3::Zero();
    for (int r = c.row0; r < c.row0 + c.nrows; ++r)
      imp += lambda[r] * ContactRowDirection(c, p.rows[static_cast<size_t>(r)], cp, nullptr);
    P[i] = imp.dot(c.n_W);
  }
  return 0;
}

}  // namespace kanesim::rt
