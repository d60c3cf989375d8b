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

#include "runtime/kane/kane.h"

namespace kanesim::rt {

namespace {

// Spatial inertia about a point o, in blocks, of a body or subtree with mass m, first
// moment h = m (c - o) and rotational inertia J about o (world axes), mapping the twist
// [v_o; w] to the wrench [f; n_o]:
//   Ic = [m 1, -[h]x;  [h]x, J].                                                  (6)
// A body's own, with central inertia I:
//   h = m x,  J = I + m (|x|^2 1 - x x^T),  x = c - o.                              (7)
// Moved from point a to point b (the twist at b seen at a), r = a - b, by the identity
// [a]x [b]x = b a^T - (a . b) 1 applied to X^T Ic X, X = [1, -[r]x; 0, 1]:
//   h_b = h_a + m r,   J_b = J_a + 2 (h_a . r) 1 - r h_a^T - h_a r^T + m (|r|^2 1 - r r^T).  (8)
// Only the blocks are written: no 3x3 or 6x6 products.
inline Vec3 FirstMoment(const Mat6& Ic) { return Vec3(Ic(5, 1), Ic(3, 2), Ic(4, 0)); }  // from [h]x

// *Ic = (6) (set) or *Ic += (6) (add).
template <bool kAdd>
inline void WriteBlocks(Mat6* Ic, double m, const Vec3& h, const Mat3& J) {
  const Mat3 H = Skew(h);
  if constexpr (kAdd) {
    for (int i = 0; i < 3; ++i) (*Ic)(i, i) += m;
    Ic->topRightCorner<3, 3>() -= H;
    Ic->bottomLeftCorner<3, 3>() += H;
    Ic->bottomRightCorner<3, 3>() += J;
  } else {
    Ic->topLeftCorner<3, 3>() = m * Mat3::Identity();
    Ic->topRightCorner<3, 3>() = -H;
    Ic->bottomLeftCorner<3, 3>() = H;
    Ic->bottomRightCorner<3, 3>() = J;
  }
}

// *Ic = the spatial inertia about o of a body with mass m, centre c, central inertia I (7).
void SetSpatialInertia(Mat6* Ic, double m, const Vec3& c, const Mat3& I, const Vec3& o) {
  const Vec3 x = c - o;
  Mat3 J = I - m * x * x.transpose();
  J.diagonal().array() += m * x.squaredNorm();
  WriteBlocks<false>(Ic, m, m * x, J);
}

// *Ib += Ia moved from point a to point b (8).
void AddMovedInertia(Mat6* Ib, const Mat6& Ia, const Vec3& a, const Vec3& b) {
  const Vec3 r = a - b;
  const double m = Ia(0, 0);
  const Vec3 h = FirstMoment(Ia);
  const Vec3 s = h + 0.5 * m * r;  // -r h^T - h r^T - m r r^T = -(r s^T + s r^T)
  Mat3 J = Ia.bottomRightCorner<3, 3>() - r * s.transpose() - s * r.transpose();
  J.diagonal().array() += 2.0 * h.dot(r) + m * r.squaredNorm();
  WriteBlocks<true>(Ib, m, h + m * r, J);
}

// Moves a wrench [f; n_a] to point b: n_b = n_a + (a - b) x f.
inline Vec6 MoveWrench(const Vec6& w, const Vec3& a, const Vec3& b) {
  Vec6 x = w;
  x.tail<3>() += (a - b).cross(w.head<3>());
  return x;
}

}  // namespace

Vec6 BiasBracket(const Program& p, const Workspace& ws, int L) {
  const auto uL = static_cast<size_t>(L);
  const Mat3& I = ws.I_W[uL];
  const Vec3& w = ws.w_WB[uL];
  Vec6 W;
  W.head<3>() = ws.F_W[uL] - p.bodies[uL].mass * ws.a_bias_cm[uL];
  W.tail<3>() = ws.T_W[uL] - I * ws.alpha_bias[uL] - w.cross(I * w);
  return W;
}

// Each body's spatial inertia about its origin, the composites Ic (leaves to root:
// children follow parents), then (4): each free speed s pushes its wrench Ic h_s up to the
// root. Writes the lower triangle of *M.
void AssembleMass(const Program& p, Workspace& ws, Eigen::MatrixXd* M) {
  const int K = static_cast<int>(p.bodies.size());
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    SetSpatialInertia(&ws.Ic[uL], p.bodies[uL].mass, ws.p_WBcm[uL], ws.I_W[uL], ws.p_WB[uL]);
  }
  for (int L = K - 1; L >= 0; --L) {
    const int P = p.joints[static_cast<size_t>(L)].parent;
    if (P < 0) continue;
    const auto uL = static_cast<size_t>(L), uP = static_cast<size_t>(P);
    AddMovedInertia(&ws.Ic[uP], ws.Ic[uL], ws.p_WB[uL], ws.p_WB[uP]);
  }
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const TreeJoint& j = p.joints[uL];
    for (int k = 0; k < j.nu; ++k) {
      const int s = j.u0 + k;
      const int fs = p.u_free_of[static_cast<size_t>(s)];
      if (fs < 0) continue;
      Vec6 F = ws.Ic[uL] * ws.H_W.col(s);
      for (int k2 = 0; k2 <= k; ++k2) {
        const int f2 = p.u_free_of[static_cast<size_t>(j.u0 + k2)];
        if (f2 >= 0) (*M)(fs, f2) = ws.H_W.col(j.u0 + k2).dot(F);
      }
      for (int B = L, A = j.parent; A >= 0; B = A, A = p.joints[static_cast<size_t>(A)].parent) {
        const auto uA = static_cast<size_t>(A);
        F.tail<3>() += (ws.p_WB[static_cast<size_t>(B)] - ws.p_WB[uA]).cross(F.head<3>());  // move to o_A
        const TreeJoint& ja = p.joints[uA];
        for (int r = ja.u0; r < ja.u0 + ja.nu; ++r) {
          const int fr = p.u_free_of[static_cast<size_t>(r)];
          if (fr >= 0) (*M)(fs, fr) = ws.H_W.col(r).dot(F);  // lower triangle: fr < fs
        }
      }
    }
  }
}

void AssembleDense(const Program& p, Workspace& ws) {
  AssembleMass(p, ws, &ws.M);
  // Each body's bracketed wrench about its origin (set: no zeroing between calls), the
  // subtree sums, then (5).
  const int K = static_cast<int>(p.bodies.size());
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    ws.Wc[uL] = MoveWrench(BiasBracket(p, ws, L), ws.p_WBcm[uL], ws.p_WB[uL]);
  }
  for (int L = K - 1; L >= 0; --L) {
    const int P = p.joints[static_cast<size_t>(L)].parent;
    if (P < 0) continue;
    const auto uL = static_cast<size_t>(L), uP = static_cast<size_t>(P);
    ws.Wc[uP] += MoveWrench(ws.Wc[uL], ws.p_WB[uL], ws.p_WB[uP]);
  }
  for (int L = 0; L < K; ++L) {
    const TreeJoint& j = p.joints[static_cast<size_t>(L)];
    for (int s = j.u0; s < j.u0 + j.nu; ++s) {
      const int fs = p.u_free_of[static_cast<size_t>(s)];
      if (fs >= 0) ws.f[fs] = ws.H_W.col(s).dot(ws.Wc[static_cast<size_t>(L)]) + ws.Q[s];  // (5)
    }
  }
}

int SolveDense(const Program& p, Workspace& ws) {
  if (p.nu == 0) return 0;
  AssembleDense(p, ws);

  const double scale = ws.M.diagonal().cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) return SingularMassMatrix(ws);
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
    if (ws.ldlt->info() != Eigen::Success) return SingularMassMatrix(ws);
    const auto D = ws.ldlt->vectorD();
    if (D.minCoeff() <= kSingularPivot * scale) return SingularMassMatrix(ws);
    ws.ldlt->solveInPlace(ws.f);
  }
  for (int i = 0; i < p.nu; ++i) ws.udot[p.u_free[static_cast<size_t>(i)]] = ws.f[i];
  return 0;
}

}  // namespace kanesim::rt
