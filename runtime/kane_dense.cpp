// Dense path: Kane's equations assembled from the tangent basis (Lesser eqs. 22-25):
//
//   F_r  = sum_L (F_L . v_{L,r} + T_L . w_{L,r}) + Q_r                          (1) active
//   F*_r = -sum_L (m_L a_L . v_{L,r} + (I_L alpha_L + w_L x I_L w_L) . w_{L,r})   (2) inertia
//   a_L = a_bias_L + sum_s v_{L,s} udot_s,  alpha_L = alpha_bias_L + sum_s w_{L,s} udot_s
//   F_r + F*_r = 0   =>   M udot = f,                                            (3)
//   M_rs = sum_L tau_{L,r}^T Mb_L tau_{L,s},   Mb_L = diag(m_L 1, I_L)
//   f_r  = sum_L tau_{L,r}^T [F_L - m_L a_bias_L;  T_L - I_L alpha_bias_L - w_L x I_L w_L] + Q_r
//
// where tau_{L,r} = [v_{L,r}; w_{L,r}] is non-zero only for bodies L below joint J(r)
// and equals the joint twist h_r (at the joint point o_J) carried rigidly to c_L. The
// sums over L are therefore grouped per subtree (the composite-rigid-body grouping,
// Featherstone 2008 §6.2), which makes the assembly O(sum of depths) instead of
// O(sum of depth^2):
//   M_rs = h_r^T X_{J(s)->J(r)}^* Ic_{J(s)} h_s    (J(r) an ancestor of or equal to J(s))  (4)
//   f_r  = h_r^T Wc_{J(r)} + Q_r                                                         (5)
// with Ic_J the spatial inertia of the subtree below J about o_J and Wc_J the sum of
// the subtree's bracketed wrenches about o_J; X^* moves a wrench between points.
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

Mat3 Skew(const Vec3& v) {
  Mat3 K;
  K << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return K;
}

// Spatial inertia about point o of a body with mass m, centre c and central inertia I
// (world axes), mapping the twist [v_o; w] to the wrench [f; n_o]:
//   [m 1, -m D; m D, I - m D D],  D = [c - o]x.
Mat6 SpatialInertia(double m, const Vec3& c, const Mat3& I, const Vec3& o) {
  const Mat3 D = Skew(c - o);
  Mat6 S;
  S.topLeftCorner<3, 3>() = m * Mat3::Identity();
  S.topRightCorner<3, 3>() = -m * D;
  S.bottomLeftCorner<3, 3>() = m * D;
  S.bottomRightCorner<3, 3>() = I - m * D * D;
  return S;
}

// Moves a spatial inertia from point a to point b: Ic_b = X^T Ic_a X with
// X = [1, -R; 0, 1], R = [a - b]x (the twist at b seen at a). In blocks, with
// Ic_a = [A, B; B^T, D]:  Ic_b = [A, B - A R; B^T + R A, D + R B - B^T R - R A R].
Mat6 MoveInertia(const Mat6& Ia, const Vec3& a, const Vec3& b) {
  const Mat3 R = Skew(a - b);
  const Mat3 A = Ia.topLeftCorner<3, 3>(), B = Ia.topRightCorner<3, 3>(), D = Ia.bottomRightCorner<3, 3>();
  const Mat3 AR = A * R;
  const Mat3 RB = R * B;
  Mat6 Ib;
  Ib.topLeftCorner<3, 3>() = A;
  Ib.topRightCorner<3, 3>() = B - AR;
  Ib.bottomLeftCorner<3, 3>() = B.transpose() - AR.transpose();  // R A = -(A R)^T (A symmetric)
  Ib.bottomRightCorner<3, 3>() = D + RB + RB.transpose() + AR.transpose() * R;  // -B^T R = (R B)^T, -R A R = (AR)^T R
  return Ib;
}

// Moves a wrench [f; n_a] to point b: n_b = n_a + (a - b) x f.
inline Vec6 MoveWrench(const Vec6& w, const Vec3& a, const Vec3& b) {
  Vec6 x = w;
  x.tail<3>() += (a - b).cross(w.head<3>());
  return x;
}

}  // namespace

void AssembleDense(const Program& p, Workspace& ws) {
  const int K = static_cast<int>(p.bodies.size());
  // Composite inertias and wrenches, leaves to root (children follow parents).
  for (int L = K - 1; L >= 0; --L) {
    const auto uL = static_cast<size_t>(L);
    const TreeBody& b = p.bodies[uL];
    const Vec3& o = ws.p_WB[uL];
    const Vec3& c = ws.p_WBcm[uL];
    ws.Ic[uL] += SpatialInertia(b.mass, c, ws.I_W[uL], o);
    Vec6 w;
    w.head<3>() = ws.F_W[uL] - b.mass * ws.a_bias_cm[uL];
    w.tail<3>() = ws.T_W[uL] - ws.I_W[uL] * ws.alpha_bias[uL] - ws.w_WB[uL].cross(ws.I_W[uL] * ws.w_WB[uL]);
    ws.Wc[uL] += MoveWrench(w, c, o);
    const int P = p.joints[uL].parent;
    if (P >= 0) {
      const auto uP = static_cast<size_t>(P);
      ws.Ic[uP] += MoveInertia(ws.Ic[uL], o, ws.p_WB[uP]);
      ws.Wc[uP] += MoveWrench(ws.Wc[uL], o, ws.p_WB[uP]);
    }
  }
  // (4) and (5): each free speed s pushes its wrench Ic h_s up to the root.
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const TreeJoint& j = p.joints[uL];
    for (int k = 0; k < j.nu; ++k) {
      const int s = j.u0 + k;
      const int fs = p.u_free_of[static_cast<size_t>(s)];
      if (fs < 0) continue;
      ws.f[fs] = ws.H_W.col(s).dot(ws.Wc[uL]) + ws.Q[s];  // (5)
      Vec6 F = ws.Ic[uL] * ws.H_W.col(s);
      for (int k2 = 0; k2 <= k; ++k2) {
        const int f2 = p.u_free_of[static_cast<size_t>(j.u0 + k2)];
        if (f2 >= 0) ws.M(fs, f2) = ws.H_W.col(j.u0 + k2).dot(F);
      }
      for (int B = L, A = j.parent; A >= 0; B = A, A = p.joints[static_cast<size_t>(A)].parent) {
        const auto uA = static_cast<size_t>(A);
        F.tail<3>() += (ws.p_WB[static_cast<size_t>(B)] - ws.p_WB[uA]).cross(F.head<3>());  // move to o_A
        const TreeJoint& ja = p.joints[uA];
        for (int r = ja.u0; r < ja.u0 + ja.nu; ++r) {
          const int fr = p.u_free_of[static_cast<size_t>(r)];
          if (fr >= 0) ws.M(fs, fr) = ws.H_W.col(r).dot(F);  // lower triangle: fr < fs
        }
      }
    }
  }
  for (int L = 0; L < K; ++L) {
    ws.Ic[static_cast<size_t>(L)].setZero();
    ws.Wc[static_cast<size_t>(L)].setZero();
  }
}

int SolveDense(const Program& p, Workspace& ws) {
  if (p.nu == 0) return 0;
  AssembleDense(p, ws);

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
