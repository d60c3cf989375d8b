// Closed loops on the reduced form: Kane's equations on the constrained tangent basis
// beta (Lesser eqs. 49-51; the rows, their Jacobian A and the partition of the free speeds
// are runtime/constraints/constraints.cpp's, whose eqs. (7)-(10) this file solves), and
// the projection onto the constraint manifold by the scene's path.
//   beta  = [1 on ind;  -A_dep^+ A_ind on dep]      (constrained tangent basis, eq. 51) (8)
//   udot  = beta z + udot_p,   udot_p = [0 on ind;  -A_dep^+ c on dep]                   (9)
//   (beta^T M beta) z = beta^T (f - M udot_p)        (Kane's equations on beta)         (10)
#include <cmath>

#include "runtime/constraints/constraints.h"
#include "runtime/kane/kane.h"

namespace kanesim::rt {

int ProjectState(const Program& p, Workspace& ws) {
  if (p.rows.empty()) return 0;
  if (p.solver == SolverPath::Sparse) return ProjectStateSparse(p, ws);
  return ProjectStateByPartition(p, ws);
}

namespace {

// Entry (i, j) of the symmetric mass matrix from the lower triangle AssembleDense fills.
inline double MassEntry(const Eigen::MatrixXd& M, int i, int j) { return i >= j ? M(i, j) : M(j, i); }

// (10) through M: the composite-rigid-body M of kane_dense.cpp, then on the structure of
// beta (8): column c of beta is 1 at speed ind[c] and non-zero elsewhere only at the rank
// dependent speeds, and udot_p (9) only at those, so
//   (M beta)_c = M_{:,ind[c]} + sum_k beta_{dep[k],c} M_{:,dep[k]},
//   Mr_cd = (M beta)_{ind[c],d} + sum_k beta_{dep[k],c} (M beta)_{dep[k],d},
// nu (1 + rank) per column instead of nu^2, read from M's lower triangle directly.
void ReduceThroughM(const Program& p, Workspace& ws) {
  AssembleDense(p, ws);
  const int nu = p.nu, rank = p.loop_rank, nind = nu - rank;
  const auto dep = [&](int k) { return ws.dep[static_cast<size_t>(k)]; };
  const auto ind = [&](int c) { return ws.ind[static_cast<size_t>(c)]; };
  // (10): f - M udot_p.
  for (int k = 0; k < rank; ++k) {
    const int s = dep(k);
    const double x = ws.udot_p[s];
    for (int i = 0; i < nu; ++i) ws.f[i] -= MassEntry(ws.M, i, s) * x;
  }
  for (int c = 0; c < nind; ++c) {
    const int s = ind(c);
    for (int i = 0; i < nu; ++i) ws.MB(i, c) = MassEntry(ws.M, i, s);
    for (int k = 0; k < rank; ++k) {
      const double b = ws.beta(dep(k), c);
      for (int i = 0; i < nu; ++i) ws.MB(i, c) += MassEntry(ws.M, i, dep(k)) * b;
    }
  }
  for (int c = 0; c < nind; ++c) {
    double fc = ws.f[ind(c)];
    for (int k = 0; k < rank; ++k) fc += ws.beta(dep(k), c) * ws.f[dep(k)];
    ws.fr[c] = fc;
    for (int d = 0; d <= c; ++d) {  // lower triangle: what the Cholesky reads
      double m = ws.MB(ind(c), d);
      for (int k = 0; k < rank; ++k) m += ws.beta(dep(k), c) * ws.MB(dep(k), d);
      ws.Mr(c, d) = m;
    }
  }
}

// (10) by Kane's method itself, on the constrained partial velocities: column c of beta
// is a set of joint speeds, and the twist every body then has is its partial twist for
// the independent speed c, T_{L,c} = sum_s tau_{L,s} beta_{s,c} (Lesser eq. 51). A
// velocity pass without bias terms gives it (at the body origins o_L, then carried to the
// mass centres), and one more with the joint accelerations udot_p gives the particular
// accelerations A_{p,L}. With W_L the bracketed wrench of kane_dense.cpp eq. 2 (kane.h
// BiasBracket) and Mb_L = diag(m_L 1, I_L):
//   Mr_cd = sum_L T_{L,c}^T Mb_L T_{L,d}                                                (11)
//   fr_c  = sum_L T_{L,c}^T (W_L - Mb_L A_{p,L}) + sum_s beta_{s,c} Q_s                  (12)
// O(K nind^2), against the composite M's O(sum of depths) + O(nu nind (1 + rank)): the
// cheaper one for a mechanism with few degrees of freedom (PassesCheaper).
void ReduceByPasses(const Program& p, Workspace& ws) {
  const int nind = p.nu - p.loop_rank;
  const int K = static_cast<int>(p.bodies.size());
  ws.fr.setZero();
  ws.Mr.setZero();
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const TreeJoint& j = p.joints[uL];
    auto T = ws.beta_twists.middleCols(static_cast<Eigen::Index>(L) * nind, nind);
    Vec6& Ap = ws.accel_p[uL];
    if (j.parent >= 0) {  // the parent's twists carried to o_L: v += w x (o_L - o_P)
      const auto uP = static_cast<size_t>(j.parent);
      const Vec3 r = ws.p_WB[uL] - ws.p_WB[uP];
      T = ws.beta_twists.middleCols(static_cast<Eigen::Index>(j.parent) * nind, nind);
      for (int c = 0; c < nind; ++c) T.col(c).head<3>() += T.col(c).tail<3>().cross(r);
      Ap = ws.accel_p[uP];
      Ap.head<3>() += Ap.tail<3>().cross(r);
    } else {
      T.setZero();
      Ap.setZero();
    }
    for (int k = 0; k < j.nu; ++k) {
      const int fs = p.u_free_of[static_cast<size_t>(j.u0 + k)];
      if (fs < 0) continue;  // prescribed: in the bias accelerations already
      const auto h = ws.H_W.col(j.u0 + k);
      for (int c = 0; c < nind; ++c) T.col(c) += h * ws.beta(fs, c);
      Ap += h * ws.udot_p[fs];
      const double Qs = ws.Q[j.u0 + k];
      for (int c = 0; c < nind; ++c) ws.fr[c] += ws.beta(fs, c) * Qs;  // (12), last sum
    }
    // Body L's share of (11) and (12), at its mass centre.
    const TreeBody& b = p.bodies[uL];
    const Mat3& I = ws.I_W[uL];
    const Vec3 x = ws.p_WBcm[uL] - ws.p_WB[uL];
    const Vec3 alpha_p = Ap.tail<3>();
    const Vec3 a_p = Ap.head<3>() + alpha_p.cross(x);
    const Vec6 W = BiasBracket(p, ws, L);  // minus Mb_L A_p,L, eq. (12)
    const Vec3 Wf = W.head<3>() - b.mass * a_p;
    const Vec3 Wt = W.tail<3>() - I * alpha_p;
    for (int c = 0; c < nind; ++c) {  // partial twist c at the mass centre: (v_cm_c, w_c)
      const Vec3 w_c = T.col(c).tail<3>();
      const Vec3 v_cm_c = T.col(c).head<3>() + w_c.cross(x);
      ws.fr[c] += v_cm_c.dot(Wf) + w_c.dot(Wt);
      const Vec3 mv = b.mass * v_cm_c, Iw = I * w_c;
      for (int d = 0; d <= c; ++d) {
        const Vec3 w_d = T.col(d).tail<3>();
        const Vec3 v_cm_d = T.col(d).head<3>() + w_d.cross(x);
        ws.Mr(c, d) += v_cm_d.dot(mv) + w_d.dot(Iw);
      }
    }
  }
}

}  // namespace

bool PassesCheaper(int dof) { return dof <= kPassesMaxDof; }

int SolveConstrained(const Program& p, Workspace& ws) {
  if (p.nu == 0) return 0;
  ConstraintBias(p, ws);
  const int nu = p.nu, rank = p.loop_rank, nind = nu - rank;
  const auto dep = [&](int k) { return ws.dep[static_cast<size_t>(k)]; };
  const auto ind = [&](int c) { return ws.ind[static_cast<size_t>(c)]; };
  // udot_p (9) and beta (8).
  ws.udot_p.setZero();
  if (rank > 0) {
    GatherActive(p, ws.cbias, &ws.active_rhs);
    SolveDependent(ws, ws.active_rhs, &ws.dep_solution);
    for (int k = 0; k < rank; ++k) ws.udot_p[dep(k)] = -ws.dep_solution[k];
  }
  ws.beta.setZero();
  for (int c = 0; c < nind; ++c) {
    const int s = ind(c);
    ws.beta(s, c) = 1.0;
    if (rank == 0) continue;
    ws.active_rhs = ws.A.col(s);
    SolveDependent(ws, ws.active_rhs, &ws.dep_solution);
    for (int k = 0; k < rank; ++k) ws.beta(dep(k), c) = -ws.dep_solution[k];
  }
  if (p.reduce_by_passes)
    ReduceByPasses(p, ws);
  else
    ReduceThroughM(p, ws);
  if (nind > 0) {
    ws.llt_r->compute(ws.Mr);
    if (ws.llt_r->info() != Eigen::Success) {
      ws.error = "singular reduced mass matrix (closed loop)";
      return -1;
    }
    ws.llt_r->solveInPlace(ws.fr);
    // udot = beta z + udot_p (9).
    for (int c = 0; c < nind; ++c) ws.udot_p[ind(c)] += ws.fr[c];
    for (int k = 0; k < rank; ++k) {
      double x = 0.0;
      for (int c = 0; c < nind; ++c) x += ws.beta(dep(k), c) * ws.fr[c];
      ws.udot_p[dep(k)] += x;
    }
  }
  for (int i = 0; i < nu; ++i) ws.udot[p.u_free[static_cast<size_t>(i)]] = ws.udot_p[i];
  return 0;
}

}  // namespace kanesim::rt
