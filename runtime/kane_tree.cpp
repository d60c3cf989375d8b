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
// follow parents in tree order); step L adds Mb_L and -w_L to its children's shares, and
// the first child the pass reaches writes its share into the parent, the others add
// (TreeLayout::first_share), so nothing is zeroed or built in a pass of its own.
// Forward pass: (5) and (1) for L = 0 .. K-1.
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
// upper-right block B and the upper triangles of A and C only; the lower-left block and
// the strict lower triangles of A and C are stale. The body inertias (PutBody), the
// one-column elimination of a revolute joint (EliminateAngular) and MoveInertia read and
// write only those; every other use calls Mirror first.
inline void Mirror(Mat6* Ia) {
  Mat6& M = *Ia;
  M.bottomLeftCorner<3, 3>() = M.topRightCorner<3, 3>().transpose();
  M(1, 0) = M(0, 1), M(2, 0) = M(0, 2), M(2, 1) = M(1, 2);
  M(4, 3) = M(3, 4), M(5, 3) = M(3, 5), M(5, 4) = M(4, 5);
}

// x = v, or x += v when kAdd.
template <bool kAdd>
inline void Put(double& x, double v) {
  if constexpr (kAdd)
    x += v;
  else
    x = v;
}

// Body L's own spatial inertia Mb_L about o_L (mass m, central inertia I, world axes,
// r = c_L - o_L), mapping the acceleration [a_o; alpha] to the wrench [f; n_o]:
//   [m 1, -m D; m D, I - m D D],  D = [r]x,  -D D = |r|^2 1 - r r^T,
// and -w_L = [-f; -n - r x f] (f, n the wrench w_L at c_L): the leaf values of (6), (7),
// written into Ia, pa, or added to the children's shares there when kAdd (kBlocks).
template <bool kAdd>
void PutBody(double m, const Vec3& r, const Mat3& I, const Vec3& f, const Vec3& n, Mat6* Ia, Vec6* pa) {
  Mat6& M = *Ia;
  const double x = m * r.x(), y = m * r.y(), z = m * r.z();  // m r
  const double mrr = x * r.x() + y * r.y() + z * r.z();
  Put<kAdd>(M(0, 0), m), Put<kAdd>(M(1, 1), m), Put<kAdd>(M(2, 2), m);  // A = m 1
  if constexpr (!kAdd) M(0, 1) = 0.0, M(0, 2) = 0.0, M(1, 2) = 0.0;
  Put<kAdd>(M(1, 3), -z), Put<kAdd>(M(2, 3), y);  // B = -m D
  Put<kAdd>(M(0, 4), z), Put<kAdd>(M(2, 4), -x);
  Put<kAdd>(M(0, 5), -y), Put<kAdd>(M(1, 5), x);
  if constexpr (!kAdd) M(0, 3) = 0.0, M(1, 4) = 0.0, M(2, 5) = 0.0;
  Put<kAdd>(M(3, 3), I(0, 0) + mrr - x * r.x()), Put<kAdd>(M(3, 4), I(0, 1) - x * r.y());  // C = I - m D D
  Put<kAdd>(M(4, 4), I(1, 1) + mrr - y * r.y()), Put<kAdd>(M(3, 5), I(0, 2) - x * r.z());
  Put<kAdd>(M(5, 5), I(2, 2) + mrr - z * r.z()), Put<kAdd>(M(4, 5), I(1, 2) - y * r.z());
  Vec6& p = *pa;
  Put<kAdd>(p[0], -f.x()), Put<kAdd>(p[1], -f.y()), Put<kAdd>(p[2], -f.z());
  Put<kAdd>(p[3], -n.x() - (r.y() * f.z() - r.z() * f.y()));
  Put<kAdd>(p[4], -n.y() - (r.z() * f.x() - r.x() * f.z()));
  Put<kAdd>(p[5], -n.z() - (r.x() * f.y() - r.y() * f.x()));
}

// X*_LP Ia X_LP of (6): the inertia Ia about o_L moved to o_P, with X = [1, -R; 0, 1],
// R = [r]x, r = o_L - o_P. With Ia = [A, B; B^T, C] (A, C symmetric) it is
//   [A, B + G; B^T + G^T, C + R B + B^T R^T + R A R^T],  G = A R^T (row i: r x A_i),
// and with F = R (B + G/2) the lower-right block is C + F + F^T (R A R^T = R G is
// symmetric), so every product is a column-wise cross product with r. Written into Ib
// (the parent's first share), or added to it when kAdd; kBlocks on both sides.
template <bool kAdd>
void MoveInertia(const Mat6& Ia, const Vec3& r, Mat6* Ib) {
  const Mat6& M = Ia;
  Mat6& N = *Ib;
  const double r0 = r.x(), r1 = r.y(), r2 = r.z();
  const double a00 = M(0, 0), a01 = M(0, 1), a02 = M(0, 2), a11 = M(1, 1), a12 = M(1, 2), a22 = M(2, 2);
  // G(i, k) = (r x A_i)_k, A_i = column i of A.
  const double g00 = r1 * a02 - r2 * a01, g01 = r2 * a00 - r0 * a02, g02 = r0 * a01 - r1 * a00;
  const double g10 = r1 * a12 - r2 * a11, g11 = r2 * a01 - r0 * a12, g12 = r0 * a11 - r1 * a01;
  const double g20 = r1 * a22 - r2 * a12, g21 = r2 * a02 - r0 * a22, g22 = r0 * a12 - r1 * a02;
  const double G[3][3] = {{g00, g01, g02}, {g10, g11, g12}, {g20, g21, g22}};
  double F[3][3];  // F(i, k) = (r x E_k)_i, E = B + G / 2
  for (int k = 0; k < 3; ++k) {
    const double e0 = M(0, 3 + k) + 0.5 * G[0][k], e1 = M(1, 3 + k) + 0.5 * G[1][k], e2 = M(2, 3 + k) + 0.5 * G[2][k];
    F[0][k] = r1 * e2 - r2 * e1;
    F[1][k] = r2 * e0 - r0 * e2;
    F[2][k] = r0 * e1 - r1 * e0;
  }
  Put<kAdd>(N(0, 0), a00), Put<kAdd>(N(0, 1), a01), Put<kAdd>(N(0, 2), a02);
  Put<kAdd>(N(1, 1), a11), Put<kAdd>(N(1, 2), a12), Put<kAdd>(N(2, 2), a22);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) Put<kAdd>(N(i, 3 + k), M(i, 3 + k) + G[i][k]);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i <= k; ++i) Put<kAdd>(N(3 + i, 3 + k), M(3 + i, 3 + k) + F[i][k] + F[k][i]);
}

// A wrench [f; n_a] moved to point b: n_b = n_a + r x f, r = a - b; written into wb, or
// added to it when kAdd.
template <bool kAdd>
inline void MoveWrench(const Vec6& w, const Vec3& r, Vec6* wb) {
  Vec6& W = *wb;
  const double f0 = w[0], f1 = w[1], f2 = w[2];
  Put<kAdd>(W[0], f0), Put<kAdd>(W[1], f1), Put<kAdd>(W[2], f2);
  Put<kAdd>(W[3], w[3] + r.y() * f2 - r.z() * f1);
  Put<kAdd>(W[4], w[4] + r.z() * f0 - r.x() * f2);
  Put<kAdd>(W[5], w[5] + r.x() * f1 - r.y() * f0);
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

// One free speed on a revolute joint in tree direction (the common case): S_L = [0; h],
// so only Ia's right half and pa's torque enter (4): U = [B h; C h], d = h . C h. The
// bracket of (6) updates B and the upper triangles of A and C only (kBlocks).
bool EliminateAngular(const Vec3& h, double Q, double* U_data, double* Dinv_data, double* u_data, Mat6* Ia,
                      Vec6* pa, PivotRange* piv) {
  Mat6& M = *Ia;
  Vec6& p = *pa;
  const double h0 = h.x(), h1 = h.y(), h2 = h.z();
  double U[6];
  for (int i = 0; i < 3; ++i) U[i] = M(i, 3) * h0 + M(i, 4) * h1 + M(i, 5) * h2;  // (4): B h
  const double c00 = M(3, 3), c01 = M(3, 4), c02 = M(3, 5), c11 = M(4, 4), c12 = M(4, 5), c22 = M(5, 5);
  U[3] = c00 * h0 + c01 * h1 + c02 * h2;  // (4): C h
  U[4] = c01 * h0 + c11 * h1 + c12 * h2;
  U[5] = c02 * h0 + c12 * h1 + c22 * h2;
  const double d = h0 * U[3] + h1 * U[4] + h2 * U[5];
  const double u = Q - (h0 * p[3] + h1 * p[4] + h2 * p[5]);
  piv->max_diag = std::max(piv->max_diag, d);
  if (!(d > 0.0)) return false;
  piv->min_pivot_sq = std::min(piv->min_pivot_sq, d);
  const double dinv = 1.0 / d;
  *Dinv_data = dinv;
  *u_data = u;
  double Ud[6];
  for (int i = 0; i < 6; ++i) {
    U_data[i] = U[i];
    Ud[i] = U[i] * dinv;
  }
  // Bracket of (6), blocks A, B, C only (kBlocks).
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i <= k; ++i) {
      M(i, k) -= Ud[i] * U[k];
      M(3 + i, 3 + k) -= Ud[3 + i] * U[3 + k];
    }
    for (int i = 0; i < 3; ++i) M(i, 3 + k) -= Ud[i] * U[3 + k];
  }
  for (int i = 0; i < 6; ++i) p[i] += Ud[i] * u;  // bracket of (7)
  return true;
}

// One free speed, any other joint: (4) with the full column s.
bool Eliminate1(const Workspace& ws, const TreeLayout::JointBlock& J, double* U_data, double* Dinv_data,
                double* u_data, Mat6* Ia, Vec6* pa, PivotRange* piv) {
  const auto s = ws.H_W.col(J.cols[0]);
  Eigen::Map<Vec6> U(U_data);
  Mirror(Ia);
  U.noalias() = *Ia * s;  // (4)
  const double d = s.dot(U);
  const double u = ws.Q[J.cols[0]] - s.dot(*pa);
  piv->max_diag = std::max(piv->max_diag, d);
  if (!(d > 0.0)) return false;
  piv->min_pivot_sq = std::min(piv->min_pivot_sq, d);
  const double dinv = 1.0 / d;
  *Dinv_data = dinv;
  *u_data = u;
  const Vec6 Ud = U * dinv;
  Ia->noalias() -= Ud * U.transpose();  // bracket of (6)
  *pa += Ud * u;                        // bracket of (7)
  return true;
}

void Substitute1(const TreeLayout::JointBlock& J, const double* U_data, const double* Dinv_data, const double* u_data,
                 const Vec6& AP, Workspace& ws, Vec6* A) {
  const Eigen::Map<const Vec6> U(U_data);
  const double ud = *Dinv_data * (*u_data - U.dot(AP));  // (5)
  *A += ws.H_W.col(J.cols[0]) * ud;                     // (1)
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
  // The backward pass reaches a parent's children from the last one in tree order: that
  // one writes its share, the others add theirs.
  layout->first_share.assign(p.joints.size(), 0);
  layout->has_children.assign(p.joints.size(), 0);
  for (size_t L = p.joints.size(); L-- > 0;) {
    const int P = layout->parent[L];
    if (P < 0) continue;
    const auto uP = static_cast<size_t>(P);
    layout->first_share[L] = !layout->has_children[uP];
    layout->has_children[uP] = 1;
  }
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
  // Backward pass, leaves to root: (4), (6), (7); a child moves its share into its parent.
  for (int L = K - 1; L >= 0; --L) {
    const auto uL = static_cast<size_t>(L);
    const TreeLayout::JointBlock& J = T.joints[uL];
    Mat6& Ia = ws.tree_Ia[uL];
    Vec6& pa = ws.tree_pa[uL];
    const Vec3& o = ws.p_WB[uL];
    {  // Body L's own inertia Mb_L and -w_L about o_L: (6), (7) at a leaf, else added.
      const double m = p.bodies[uL].mass;
      const Mat3& I = ws.I_W[uL];
      const Vec3& w_B = ws.w_WB[uL];
      const Vec3 r = ws.p_WBcm[uL] - o;
      const Vec3 f = ws.F_W[uL] - m * ws.a_bias_cm[uL];  // w_L at c_L
      const Vec3 n = ws.T_W[uL] - I * ws.alpha_bias[uL] - w_B.cross(I * w_B);
      if (T.has_children[uL])
        PutBody<true>(m, r, I, f, n, &Ia, &pa);
      else
        PutBody<false>(m, r, I, f, n, &Ia, &pa);
    }
    double* U = ws.tree_U.data() + 6 * J.f0;
    const bool ok = J.angular ? EliminateAngular(ws.H_W.col(J.cols[0]).tail<3>(), ws.Q[J.cols[0]], U,
                                                 ws.tree_Dinv.data() + J.d0, ws.tree_u.data() + J.f0, &Ia, &pa, &piv)
                              : EliminateJoint(ws, J, U, ws.tree_Dinv.data() + J.d0, ws.tree_u.data() + J.f0, &Ia,
                                               &pa, &piv);
    if (!ok) return Singular(ws);
    const int P = T.parent[uL];
    if (P < 0) continue;
    const auto uP = static_cast<size_t>(P);
    const Vec3 r = o - ws.p_WB[uP];
    if (T.first_share[uL]) {
      MoveInertia<false>(Ia, r, &ws.tree_Ia[uP]);  // (6)
      MoveWrench<false>(pa, r, &ws.tree_pa[uP]);   // (7)
    } else {
      MoveInertia<true>(Ia, r, &ws.tree_Ia[uP]);
      MoveWrench<true>(pa, r, &ws.tree_pa[uP]);
    }
    // U_L^T X_LP A_P = (X_LP^T U_L)^T A_P with X_LP^T [U_v; U_w] = [U_v; U_w + r x U_v],
    // r = o_L - o_P: stored so, (5) in the forward pass waits only for A_P, not for the
    // shift of A_P to o_L as well.
    for (int k = 0; k < J.nf; ++k, U += 6) {
      U[3] += r.y() * U[2] - r.z() * U[1];
      U[4] += r.z() * U[0] - r.x() * U[2];
      U[5] += r.x() * U[1] - r.y() * U[0];
    }
  }
  if (!(piv.min_pivot_sq > kSingularPivot * piv.max_diag)) return Singular(ws);
  // Forward pass, root to leaves: (5), (1).
  for (int L = 0; L < K; ++L) {
    const auto uL = static_cast<size_t>(L);
    const TreeLayout::JointBlock& J = T.joints[uL];
    const int P = T.parent[uL];
    const double* U = ws.tree_U.data() + 6 * J.f0;
    const double* Dinv = ws.tree_Dinv.data() + J.d0;
    const double* u = ws.tree_u.data() + J.f0;
    Vec6& A = ws.tree_A[uL];
    if (P < 0) {
      A.setZero();
      SubstituteJoint(J, U, Dinv, u, A, ws, &A);
      continue;
    }
    const auto uP = static_cast<size_t>(P);
    const Vec6& AP = ws.tree_A[uP];
    const Vec3 r = ws.p_WB[uL] - ws.p_WB[uP];
    const double a0 = AP[0], a1 = AP[1], a2 = AP[2], w0 = AP[3], w1 = AP[4], w2 = AP[5];
    A[0] = a0 + w1 * r.z() - w2 * r.y();  // X_LP A_P
    A[1] = a1 + w2 * r.x() - w0 * r.z();
    A[2] = a2 + w0 * r.y() - w1 * r.x();
    if (J.angular) {
      const double ud = *Dinv * (*u - (U[0] * a0 + U[1] * a1 + U[2] * a2 + U[3] * w0 + U[4] * w1 + U[5] * w2));  // (5)
      const auto h = ws.H_W.col(J.cols[0]);
      A[3] = w0 + h[3] * ud;  // (1)
      A[4] = w1 + h[4] * ud;
      A[5] = w2 + h[5] * ud;
      ws.udot[J.cols[0]] = ud;
    } else {
      A[3] = w0, A[4] = w1, A[5] = w2;
      SubstituteJoint(J, U, Dinv, u, AP, ws, &A);
    }
  }
  return 0;
}

}  // namespace kanesim::rt
