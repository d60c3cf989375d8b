// Dense path: Kane's equations assembled from the tangent basis (Lesser eqs. 22-25):
//
//   F_r  = sum_L (F_L . v_{L,r} + T_L . w_{L,r}) + Q_r                      (1) active
//   F*_r = -sum_L (m_L a_L . v_{L,r} + (I_L alpha_L + w_L x I_L w_L) . w_{L,r})  (2) inertia
//   a_L = a_bias_L + sum_s v_{L,s} udot_s,  alpha_L = alpha_bias_L + sum_s w_{L,s} udot_s
//   F_r + F*_r = 0   =>   M udot = f,                                        (3)
//   M_rs = sum_L tau_{L,r}^T Mb_L tau_{L,s},   Mb_L = diag(m_L 1, I_L)
//   f_r  = sum_L tau_{L,r}^T [F_L - m_L a_bias_L;  T_L - I_L alpha_bias_L - w_L x I_L w_L] + Q_r
//
// where tau_{L,r} = [v_{L,r}; w_{L,r}] is non-zero only for r on L's path (the pattern
// body.path_speeds), so body L costs O(depth_L^2).
#include <cmath>

#include "runtime/kane.h"

namespace kanesim::rt {

namespace {

// A pivot of the factor below this fraction of the largest diagonal entry of M means
// the mass matrix is singular to working precision (e.g. a massless, inertia-free link).
constexpr double kSingularPivot = 1e-13;

int Singular(Workspace& ws) {
  ws.error = "singular mass matrix (a body without mass or inertia moved by a joint?)";
  return -1;
}

}  // namespace

int SolveDense(const Program& p, Workspace& ws) {
  if (p.nu == 0) return 0;
  ws.M.setZero();
  ws.f.setZero();
  const size_t K = p.bodies.size();
  for (size_t L = 0; L < K; ++L) {
    const TreeBody& b = p.bodies[L];
    const int d = static_cast<int>(b.path_speeds.size());
    if (d == 0) continue;
    const Vec3 c = ws.p_WBcm[L];
    for (int a = 0; a < d; ++a) {
      const int r = b.path_speeds[static_cast<size_t>(a)];
      const auto h = ws.H_W.col(r);
      const Vec3& o = ws.p_WB[static_cast<size_t>(p.joint_of_speed[static_cast<size_t>(r)])];
      ws.tau_L.col(a).head<3>() = h.head<3>() + h.tail<3>().cross(c - o);  // Lesser eq. 22
      ws.tau_L.col(a).tail<3>() = h.tail<3>();
    }
    ws.Mtau_L.leftCols(d).topRows<3>() = b.mass * ws.tau_L.leftCols(d).topRows<3>();
    ws.Mtau_L.leftCols(d).bottomRows<3>().noalias() = ws.I_W[L] * ws.tau_L.leftCols(d).bottomRows<3>();
    Vec6 rhs;
    const Vec3 Iw = ws.I_W[L] * ws.w_WB[L];
    rhs.head<3>() = ws.F_W[L] - b.mass * ws.a_bias_cm[L];
    rhs.tail<3>() = ws.T_W[L] - ws.I_W[L] * ws.alpha_bias[L] - ws.w_WB[L].cross(Iw);
    for (int a = 0; a < d; ++a) {
      const int fa = p.u_free_of[static_cast<size_t>(b.path_speeds[static_cast<size_t>(a)])];
      for (int e = 0; e <= a; ++e) {
        const int fe = p.u_free_of[static_cast<size_t>(b.path_speeds[static_cast<size_t>(e)])];
        const double m = ws.tau_L.col(a).dot(ws.Mtau_L.col(e));
        // Keep the lower triangle (fa >= fe holds: path speeds are in increasing order).
        ws.M(fa, fe) += m;
      }
      ws.f[fa] += ws.tau_L.col(a).dot(rhs);
    }
  }
  for (int i = 0; i < p.nu; ++i) ws.f[i] += ws.Q[p.u_free[static_cast<size_t>(i)]];

  const double scale = ws.M.diagonal().cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) return Singular(ws);
  ws.llt->compute(ws.M);  // reads the lower triangle
  bool ok = ws.llt->info() == Eigen::Success;
  if (ok) {
    const double min_pivot = ws.llt->matrixLLT().diagonal().minCoeff();
    ok = min_pivot * min_pivot > kSingularPivot * scale;
  }
  if (ok) {
    ws.llt->solveInPlace(ws.f);
  } else {
    // Fallback: LDLT (pivoted) tells a singular or indefinite matrix apart from a
    // badly scaled one.
    ws.M.triangularView<Eigen::StrictlyUpper>() = ws.M.transpose().triangularView<Eigen::StrictlyUpper>();
    ws.ldlt->compute(ws.M);
    if (ws.ldlt->info() != Eigen::Success) return Singular(ws);
    const auto D = ws.ldlt->vectorD();
    if (D.minCoeff() <= kSingularPivot * scale) return Singular(ws);
    ws.ldlt->solveInPlace(ws.f);
  }
  for (int i = 0; i < p.nu; ++i) ws.udot[p.u_free[static_cast<size_t>(i)]] = ws.f[i];
  return 0;
}

}  // namespace kanesim::rt
