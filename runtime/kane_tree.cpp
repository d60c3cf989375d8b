// Recursive path: Kane's equations of an open tree (Lesser eqs. 22-25, grouped per
// subtree as in kane_dense.cpp eq. (3)) eliminated leaves to root, then solved root to
// leaves. The unknowns are the free udot; the body accelerations are linear in them:
//
//   A_L = X_LP A_P + S_L udot_L,   X_LP A = [a + alpha x (o_L - o_P);  alpha],  A_ground = 0  (1)
//   S_L^T sum_{B in subtree(L)} X*_BL (Mb_B A_B - w_B) = Q_L                                 (2)
//
// where A_L = [a; alpha] is the part of body L's acceleration at its origin o_L that
// depends on the free udot (the rest, with free udot = 0, is in the bias accelerations),
// S_L the free columns of the joint's tangent generators H_W (twists at o_L), Mb_B the
// spatial inertia of body B about o_B, w_B = [F_B - m_B a_bias_B; T_B - I_B alpha_bias_B
// - w_B x I_B w_B] moved from c_B to o_B (the applied and bias-inertia wrench, as in the
// dense path), X*_BL moves a wrench from o_B to o_L, and Q_L the joint forces of joint L.
//
// Elimination (the articulated-body recursion, Featherstone 2008 §7.3, read as Gaussian
// block elimination of (2) in leaf-first order). Suppose that for every child C of L
//   sum_{B in subtree(C)} X*_BC (Mb_B A_B - w_B) = Ia_C A_C + pa_C.                         (3)
// Then (2) for C with (1) gives its udot in terms of its parent's acceleration:
//   U_C = Ia_C S_C,  D_C = S_C^T U_C,  u_C = Q_C - S_C^T pa_C                               (4)
//   udot_C = D_C^-1 (u_C - U_C^T X_CL A_L)                                                 (5)
// and substituting (5) into (3) makes it linear in A_L alone, so (3) holds for L with
//   Ia_L = Mb_L + sum_C X*_CL (Ia_C - U_C D_C^-1 U_C^T) X_CL                                 (6)
//   pa_L = -w_L + sum_C X*_CL (pa_C + U_C D_C^-1 u_C)                                        (7)
// (at a leaf: Ia = Mb, pa = -w). Backward pass: (4), (6), (7) for L = K-1 .. 0 (children
// follow parents in tree order). Forward pass: (5) and (1) for L = 0 .. K-1.
//
// The D_L are the pivot blocks of the mass matrix M = tau^T Mb tau eliminated in
// leaf-first order (Schur complements), so they are positive definite exactly when M is;
// a pivot below kSingularPivot of the largest diagonal entry means M is singular to
// working precision, the same test as the dense path's Cholesky.
#include "runtime/kane_tree.h"

#include <algorithm>
#include <limits>

namespace kanesim::rt {

namespace {

// A squared pivot of a D_L below this fraction of the largest diagonal entry of the D_L
// means a singular mass matrix (kane_dense.cpp uses the same bound for Cholesky).
constexpr double kSingularPivot = 1e-13;

template <int NF>
using Mat6N = Eigen::Matrix<double, 6, NF>;
template <int NF>
using MatN = Eigen::Matrix<double, NF, NF>;
template <int NF>
using VecN = Eigen::Matrix<double, NF, 1>;

// The smallest squared pivot and the largest diagonal entry of the D_L seen so far.
struct PivotRange {
  double min_pivot_sq = std::numeric_limits<double>::infinity();
  double max_diag = 0.0;
};

// kBlocks: a spatial inertia [A, B; B^T, C] (A, C symmetric) in tree_Ia is kept by its
// blocks A, B and C only; its lower-left block is stale. The one-column elimination of a
// revolute joint and AddMovedInertia read and write only A, B and C; every other use
// calls Mirror first.
inline void Mirror(Mat6* Ia) { Ia->bottomLeftCorner<3, 3>() = Ia->topRightCorner<3, 3>().transpose(); }

// Spatial inertia of a body (mass m, centre c, central inertia I, world axes) about o,
// mapping the acceleration [a_o; alpha] to the wrench [f; n_o]:
//   [m 1, -m D; m D, I - m D D],  D = [r]x,  r = c - o,  -D D = |r|^2 1 - r r^T.
void SpatialInertia(double m, const Vec3& c, const Mat3& I, const Vec3& o, Mat6* S) {
  const Vec3 r = c - o;
  const double x = m * r.x(), y = m * r.y(), z = m * r.z();  // m r
  Mat6& M = *S;
  // The blocks A = m 1, B = -m D and C = I - m D D, D = [r]x (the lower block B^T = m D
  // is not written, see kBlocks).
  M(0, 0) = m, M(1, 0) = 0.0, M(2, 0) = 0.0;
  M(0, 1) = 0.0, M(1, 1) = m, M(2, 1) = 0.0;
  M(0, 2) = 0.0, M(1, 2) = 0.0, M(2, 2) = m;
  M(0, 3) = 0.0, M(1, 3) = -z, M(2, 3) = y;
  M(0, 4) = z, M(1, 4) = 0.0, M(2, 4) = -x;
  M(0, 5) = -y, M(1, 5) = x, M(2, 5) = 0.0;
  const double mrr = x * r.x() + y * r.y() + z * r.z();
  M.bottomRightCorner<3, 3>() = I - Vec3(x, y, z) * r.transpose();
  M.bottomRightCorner<3, 3>().diagonal().array() += mrr;
}

// X*_LP Ia X_LP of (6): the inertia Ia about a moved to b, with X = [1, -R; 0, 1],
// R = [d]x, d = a - b. With Ia = [A, B; B^T, C] (A, C symmetric):
//   [A, B - A R; B^T + R A, C + R B - B^T R - R A R]
// added into Ib. With P = R A (columns d x A_j; A R = -P^T since A is symmetric):
//   B - A R = B + P^T,   -B^T R = (R B)^T,   -R A R = R P^T,
// so every product is a column-wise cross product with d.
void AddMovedInertia(const Mat6& Ia, const Vec3& a, const Vec3& b, Mat6* Ib) {
  const Vec3 d = a - b;
  Mat3 P, RB, RPt;
  for (int k = 0; k < 3; ++k) {
    P.col(k) = d.cross(Ia.block<3, 1>(0, k));
    RB.col(k) = d.cross(Ia.block<3, 1>(0, 3 + k));
  }
  for (int k = 0; k < 3; ++k) RPt.col(k) = d.cross(P.row(k).transpose());
  const Mat3 B2 = Ia.topRightCorner<3, 3>() + P.transpose();
  Ib->topLeftCorner<3, 3>() += Ia.topLeftCorner<3, 3>();
  Ib->topRightCorner<3, 3>() += B2;  // (the lower-left block: kBlocks)
  Ib->bottomRightCorner<3, 3>() += Ia.bottomRightCorner<3, 3>() + RB + RB.transpose() + RPt;
}

// A wrench [f; n_a] moved to point b: n_b = n_a + (a - b) x f.
inline void AddMovedWrench(const Vec6& w, const Vec3& a, const Vec3& b, Vec6* wb) {
  wb->head<3>() += w.head<3>();
  wb->tail<3>() += w.tail<3>() + (a - b).cross(w.head<3>());
}

// S_L: the free columns of the joint's tangent generators.
template <int NF>
Mat6N<NF> FreeColumns(const Workspace& ws, const TreeLayout::JointBlock& J) {
  if (J.contiguous) return ws.H_W.middleCols<NF>(J.cols[0]);
  Mat6N<NF> S;
  for (int k = 0; k < NF; ++k) S.col(k) = ws.H_W.col(J.cols[static_cast<size_t>(k)]);
  return S;
}

// Backward step of joint L: (4), then Ia and pa turned into the brackets of (6) and (7).
// Returns false when D_L is not positive definite.
template <int NF>
bool Eliminate(const Workspace& ws, const TreeLayout::JointBlock& J, double* U_data, double* Dinv_data,
               double* u_data, Mat6* Ia, Vec6* pa, PivotRange* piv) {
  Mirror(Ia);
  const Mat6N<NF> S = FreeColumns<NF>(ws, J);
  Eigen::Map<Mat6N<NF>> U(U_data);
  Eigen::Map<MatN<NF>> Dinv(Dinv_data);
  Eigen::Map<VecN<NF>> u(u_data);
  U.noalias() = *Ia * S;                        // (4)
  const MatN<NF> D = S.transpose() * U;         // (4)
  for (int k = 0; k < NF; ++k) u[k] = ws.Q[J.cols[static_cast<size_t>(k)]] - S.col(k).dot(*pa);  // (4)
  piv->max_diag = std::max(piv->max_diag, D.diagonal().maxCoeff());
  if constexpr (NF == 1) {
    const double d = D(0, 0);
    if (!(d > 0.0)) return false;
    piv->min_pivot_sq = std::min(piv->min_pivot_sq, d);
    Dinv(0, 0) = 1.0 / d;
  } else {
    const Eigen::LLT<MatN<NF>> llt(D);
    if (llt.info() != Eigen::Success) return false;
    piv->min_pivot_sq = std::min(piv->min_pivot_sq, llt.matrixLLT().diagonal().cwiseAbs2().minCoeff());
    Dinv = llt.solve(MatN<NF>::Identity());
  }
  const Mat6N<NF> UD = U * Dinv;
  Ia->noalias() -= UD * U.transpose();  // bracket of (6)
  pa->noalias() += UD * u;              // bracket of (7)
  return true;
}

// Forward step of joint L: (5) and (1), given the parent's A_P and A = X_LP A_P; writes
// udot_L. The stored U is X_LP^T U (see SolveTree), so (5) reads A_P, not A.
template <int NF>
void Substitute(const TreeLayout::JointBlock& J, const double* U_data, const double* Dinv_data,
                const double* u_data, const Vec6& AP, Workspace& ws, Vec6* A) {
  const Eigen::Map<const Mat6N<NF>> U(U_data);
  const Eigen::Map<const MatN<NF>> Dinv(Dinv_data);
  const Eigen::Map<const VecN<NF>> u(u_data);
  const VecN<NF> ud = Dinv * (u - U.transpose() * AP);  // (5)
  *A += FreeColumns<NF>(ws, J) * ud;                    // (1)
  for (int k = 0; k < NF; ++k) ws.udot[J.cols[static_cast<size_t>(k)]] = ud[k];
}

// One free speed (the common case), S_L a single column s; on a revolute joint in tree
// direction s = [0; h] and only Ia's right half and pa's torque enter (4).
bool Eliminate1(const Workspace& ws, const TreeLayout::JointBlock& J, double* U_data, double* Dinv_data,
                double* u_data, Mat6* Ia, Vec6* pa, PivotRange* piv) {
  const auto s = ws.H_W.col(J.cols[0]);
  Eigen::Map<Vec6> U(U_data);
  double d = 0.0, u = ws.Q[J.cols[0]];
  if (J.angular) {
    const Vec3 h = s.tail<3>();
    U.head<3>().noalias() = Ia->topRightCorner<3, 3>() * h;  // (4): U = [B h; C h]
    U.tail<3>().noalias() = Ia->bottomRightCorner<3, 3>() * h;
    d = h.dot(U.tail<3>());
    u -= h.dot(pa->tail<3>());
  } else {
    Mirror(Ia);
    U.noalias() = *Ia * s;
    d = s.dot(U);
    u -= s.dot(*pa);
  }
  piv->max_diag = std::max(piv->max_diag, d);
  if (!(d > 0.0)) return false;
  piv->min_pivot_sq = std::min(piv->min_pivot_sq, d);
  const double dinv = 1.0 / d;
  *Dinv_data = dinv;
  *u_data = u;
  const Vec6 Ud = U * dinv;
  // Bracket of (6), blocks A, B, C only (kBlocks).
  Ia->topLeftCorner<3, 3>().noalias() -= Ud.head<3>() * U.head<3>().transpose();
  Ia->topRightCorner<3, 3>().noalias() -= Ud.head<3>() * U.tail<3>().transpose();
  Ia->bottomRightCorner<3, 3>().noalias() -= Ud.tail<3>() * U.tail<3>().transpose();
  *pa += Ud * u;  // bracket of (7)
  return true;
}

void Substitute1(const TreeLayout::JointBlock& J, const double* U_data, const double* Dinv_data, const double* u_data,
                 const Vec6& AP, Workspace& ws, Vec6* A) {
  const Eigen::Map<const Vec6> U(U_data);
  const double ud = *Dinv_data * (*u_data - U.dot(AP));  // (5)
  const auto s = ws.H_W.col(J.cols[0]);
  if (J.angular)
    A->tail<3>() += s.tail<3>() * ud;  // (1)
  else
    *A += s * ud;
  ws.udot[J.cols[0]] = ud;
}

// Dispatch on the joint's number of free speeds (fixed-size blocks for each).
bool EliminateJoint(const Workspace& ws, const TreeLayout::JointBlock& J, double* U, double* Dinv, double* u,
                    Mat6* Ia, Vec6* pa, PivotRange* piv) {
  switch (J.nf) {
    case 0: return true;
    case 1: return Eliminate1(ws, J, U, Dinv, u, Ia, pa, piv);
    case 2: return Eliminate<2>(ws, J, U, Dinv, u, Ia, pa, piv);
    case 3: return Eliminate<3>(ws, J, U, Dinv, u, Ia, pa, piv);
    case 4: return Eliminate<4>(ws, J, U, Dinv, u, Ia, pa, piv);
    case 5: return Eliminate<5>(ws, J, U, Dinv, u, Ia, pa, piv);
    default: return Eliminate<6>(ws, J, U, Dinv, u, Ia, pa, piv);
  }
}

void SubstituteJoint(const TreeLayout::JointBlock& J, const double* U, const double* Dinv, const double* u,
                     const Vec6& AP, Workspace& ws, Vec6* A) {
  switch (J.nf) {
    case 0: return;
    case 1: return Substitute1(J, U, Dinv, u, AP, ws, A);
    case 2: return Substitute<2>(J, U, Dinv, u, AP, ws, A);
    case 3: return Substitute<3>(J, U, Dinv, u, AP, ws, A);
    case 4: return Substitute<4>(J, U, Dinv, u, AP, ws, A);
    case 5: return Substitute<5>(J, U, Dinv, u, AP, ws, A);
    default: return Substitute<6>(J, U, Dinv, u, AP, ws, A);
  }
}

int Singular(Workspace& ws) {
  ws.error = "singular mass matrix (a body without mass or inertia moved by a joint?)";
  return -1;
}

}  // namespace

void BuildTree(Program& p) {
  auto layout = std::make_shared<TreeLayout>();
  layout->joints.resize(p.joints.size());
  layout->parent.resize(p.joints.size());
  int d0 = 0;
  for (size_t L = 0; L < p.joints.size(); ++L) {
    const TreeJoint& j = p.joints[L];
    TreeLayout::JointBlock& J = layout->joints[L];
    layout->parent[L] = j.parent;
    for (int k = 0; k < j.nu; ++k) {
      const int s = j.u0 + k;
      const int f = p.u_free_of[static_cast<size_t>(s)];
      if (f < 0) continue;
      if (J.nf == 0) J.f0 = f;
      J.cols[static_cast<size_t>(J.nf++)] = s;
    }
    J.contiguous = J.nf == j.nu;
    J.angular = J.nf == 1 && j.single_axis && j.type == flat::JointType::Revolute;
    J.d0 = d0;
    d0 += J.nf * J.nf;
  }
  layout->d_size = d0;
  p.tree = std::move(layout);
}

void InitTreeWorkspace(const Program& p, Workspace& ws) {
  const size_t K = p.bodies.size();
  ws.tree_Ia.assign(K, Mat6::Zero());
  ws.tree_pa.assign(K, Vec6::Zero());
  ws.tree_A.assign(K, Vec6::Zero());
  ws.tree_U = Eigen::VectorXd::Zero(6 * p.nu);
  ws.tree_Dinv = Eigen::VectorXd::Zero(p.tree->d_size);
  ws.tree_u = Eigen::VectorXd::Zero(p.nu);
}

int SolveTree(const Program& p, Workspace& ws) {
  if (p.nu == 0) return 0;
  const TreeLayout& T = *p.tree;
  const int K = static_cast<int>(p.bodies.size());
  PivotRange piv;
  // Each body's own inertia Mb_L and -w_L, both about o_L: the leaf values of (6), (7).
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const TreeBody& b = p.bodies[uL];
    const Vec3& o = ws.p_WB[uL];
    const Vec3& c = ws.p_WBcm[uL];
    const Mat3& I = ws.I_W[uL];
    const Vec3& w_B = ws.w_WB[uL];
    SpatialInertia(b.mass, c, I, o, &ws.tree_Ia[uL]);
    const Vec3 f = ws.F_W[uL] - b.mass * ws.a_bias_cm[uL];                      // w_L at c_L
    const Vec3 n = ws.T_W[uL] - I * ws.alpha_bias[uL] - w_B.cross(I * w_B);
    Vec6& pa = ws.tree_pa[uL];
    pa.head<3>() = -f;
    pa.tail<3>() = -n - (c - o).cross(f);
  }
  // Backward pass, leaves to root: (4), (6), (7); a child adds its share into its parent.
  for (int L = K - 1; L >= 0; --L) {
    const auto uL = static_cast<size_t>(L);
    const TreeLayout::JointBlock& J = T.joints[uL];
    Mat6& Ia = ws.tree_Ia[uL];
    Vec6& pa = ws.tree_pa[uL];
    if (!EliminateJoint(ws, J, ws.tree_U.data() + 6 * J.f0, ws.tree_Dinv.data() + J.d0, ws.tree_u.data() + J.f0,
                        &Ia, &pa, &piv))
      return Singular(ws);
    const int P = T.parent[uL];
    if (P >= 0) {
      const auto uP = static_cast<size_t>(P);
      const Vec3& o = ws.p_WB[uL];
      AddMovedInertia(Ia, o, ws.p_WB[uP], &ws.tree_Ia[uP]);  // (6)
      AddMovedWrench(pa, o, ws.p_WB[uP], &ws.tree_pa[uP]);   // (7)
      // U_L^T X_LP A_P = (X_LP^T U_L)^T A_P with X_LP^T [U_v; U_w] = [U_v; U_w + r x U_v],
      // r = o_L - o_P: stored so, (5) in the forward pass waits only for A_P, not for the
      // shift of A_P to o_L as well.
      const Vec3 r = o - ws.p_WB[uP];
      double* U = ws.tree_U.data() + 6 * J.f0;
      for (int k = 0; k < J.nf; ++k, U += 6) {
        Eigen::Map<Vec6> col(U);
        col.tail<3>() += r.cross(col.head<3>());
      }
    }
  }
  if (!(piv.min_pivot_sq > kSingularPivot * piv.max_diag)) return Singular(ws);
  // Forward pass, root to leaves: (5), (1).
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const TreeLayout::JointBlock& J = T.joints[uL];
    const int P = T.parent[uL];
    Vec6 A = Vec6::Zero();
    if (P >= 0) {
      const auto uP = static_cast<size_t>(P);
      const Vec6& AP = ws.tree_A[uP];
      A.head<3>() = AP.head<3>() + AP.tail<3>().cross(ws.p_WB[uL] - ws.p_WB[uP]);  // X_LP A_P
      A.tail<3>() = AP.tail<3>();
      SubstituteJoint(J, ws.tree_U.data() + 6 * J.f0, ws.tree_Dinv.data() + J.d0, ws.tree_u.data() + J.f0, AP, ws,
                      &A);
    } else {
      SubstituteJoint(J, ws.tree_U.data() + 6 * J.f0, ws.tree_Dinv.data() + J.d0, ws.tree_u.data() + J.f0, A, ws,
                      &A);
    }
    ws.tree_A[uL] = A;
  }
  return 0;
}

}  // namespace kanesim::rt
